# vs.sh SCENE DEPTH SPP TAG
S=$1; D=$2; N=$3; b=$4
for seed in 1 2 3 4 5 6 7 8; do
/tmp/lanterna_old render $S --method pt --source tree --spp $N --max-depth $D --width 96 --height 72 --seed $seed -o ${b}_old_$seed.exr >/dev/null 2>&1
/work/main/target/release/lanterna render $S --method pt --source tree --spp $N --max-depth $D --width 96 --height 72 --seed $seed -o ${b}_new_$seed.exr >/dev/null 2>&1
done
/work/main/.cache/venv/bin/python var.py ${b}_old ${b}_new
