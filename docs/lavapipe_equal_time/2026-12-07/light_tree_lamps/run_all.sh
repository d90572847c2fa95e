cd /tmp/lt
echo "scene,renders,mean_old,mean_new,pixel_variance_old,pixel_variance_new,variance_ratio,relative_variance_ratio" > lamps.csv
run() { sh vs.sh $1 $2 16 $3 > /dev/null; /work/main/.cache/venv/bin/python var_csv.py $3 "$4" >> lamps.csv; }
run exp.gltf 2 lx "lamps (4 tilted flat-hemisphere IES lamps + 2 hard-edged 80 deg spots + 16 points; depth 2)"
for k in 1 2 3 4 5 6; do run rs$k/s.gltf 3 rs$k "random_scene.py $k (depth 3)"; done
run /work/main/tests/data/mitsuba/punctual.gltf 4 pp "tests/data/mitsuba/punctual.gltf (depth 4)"
run /work/main/tests/data/mitsuba/ies.gltf 4 iesv "tests/data/mitsuba/ies.gltf (depth 4)"
run pn/pn.gltf 3 pn "scene generate punctual-near (depth 3)"
echo finished >> lamps.csv
