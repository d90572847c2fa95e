#!/bin/bash
# GPU session 2026-11-27 (second session of the day), first call: the guided methods'
# host work per training pass and the per-pass gap between wall and GPU time, before
# (.gpu/after/1-refit.xz, the build of refit.sh's "after") and after (.gpu/after/2-head.xz:
# refit into retired trees, flattening into staging, read-back taken in place, the
# all-passes film kept on the device), alternated, two rounds. Lines go to
# $OUT/host_after.txt. W and SPP shrink it for a dry run.
set -u
for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
mkdir -p /tmp/lbin; for x in .gpu/after/*.xz; do n=$(basename $x .xz); xz -dc $x > /tmp/lbin/$n 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('$x').read())" > /tmp/lbin/$n; chmod +x /tmp/lbin/$n; done
/tmp/lbin/2-head --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
O=$OUT/host_after.txt; W=${W:-"--width 1024 --height 576"}; SPP=${SPP:-1000}; t0=$SECONDS
echo "== start $(nvidia-smi --query-gpu=name --format=csv,noheader 2>/dev/null)" >> $O
for r in 1 2; do
  for s in street bistro-night; do
    for b in $(ls /tmp/lbin | sort); do
      for m in guided guided-ris; do
        timeout 60 /tmp/lbin/$b --log debug render scenes/$s.gltf $W --method $m --spp $SPP --seed 1 -o /tmp/g.exr 2>&1 \
          | grep -E "guiding iteration|training took|M samples/s" | sed "s|^|r$r $b $s $m: |" >> $O
      done
    done
  done
  echo "round $r done $((SECONDS-t0)) s" >> $O
done
echo "done $((SECONDS-t0)) s" >> $O
