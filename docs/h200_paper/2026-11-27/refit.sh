#!/bin/bash
# GPU session 2026-11-27, fourth call: the refit's parts (selection, training sums,
# refit, flatten) per training pass at 1024x576, 1000 spp, before (.gpu/host/0-staging.xz)
# and after (.gpu/host/1-refit.xz) the refit's per-leaf work was split among threads by
# cost and the selection's gradient computed once per record; alternated, the street
# twice. Lines go to $OUT/refit.txt. W shrinks it for a dry run.
set -u
for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
mkdir -p /tmp/host; for x in .gpu/host/*.xz; do n=$(basename $x .xz); xz -dc $x > /tmp/host/$n 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('$x').read())" > /tmp/host/$n; chmod +x /tmp/host/$n; done
/tmp/host/1-refit --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
O=$OUT/refit.txt; W=${W:-"--width 1024 --height 576"}; SPP=${SPP:-1000}; t0=$SECONDS
for run in "1 street" "1 bistro-night" "2 street"; do
  set -- $run
  for b in $(ls /tmp/host | sort); do
    for m in guided guided-ris; do
      timeout 60 /tmp/host/$b --log debug render scenes/$2.gltf $W --method $m --spp $SPP --seed 1 -o /tmp/g.exr 2>&1 \
        | grep -E "guiding iteration|training took|M samples/s" | sed "s|^|r$1 $b $2 $m: |" >> $O
    done
  done
  echo "r$1 $2 done $((SECONDS-t0))" | tee -a $O
done
