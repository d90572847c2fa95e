#!/bin/bash
# GPU session 2026-11-27, second call: (1) the driver's register statistics of the
# kernels of the builds around the one-call-site change (each old build with the
# kernel-statistics commit applied, .gpu/stats/<order>-<commit>.xz), (2) the guided
# methods' host work per training pass (read-back, refit, upload) before and after the
# kept buffers and staging, alternated (.gpu/host/{0-before,1-after}.xz).
# Run from the repository root on the GPU machine with the Vulkan loader's .deb files in
# .gl/; every line goes to $OUT/host_work.txt as it is made. W shrinks it for a dry run.
set -u
for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
unxz() { mkdir -p $2; for x in $1/*.xz; do n=$(basename $x .xz); xz -dc $x > $2/$n 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('$x').read())" > $2/$n; chmod +x $2/$n; done; }
unxz .gpu/stats /tmp/stats; unxz .gpu/host /tmp/host
/tmp/host/1-after --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
O=$OUT/host_work.txt
W=${W:-"--width 1024 --height 576"}
SPP=${SPP:-1000}
t0=$SECONDS
log() { echo "$*" | tee -a $O; }

log "== kernel statistics $((SECONDS-t0))"
for b in $(ls /tmp/stats | sort); do
  for m in pt ris guided; do
    timeout 60 /tmp/stats/$b --log debug render scenes/bistro-night.gltf --width 64 --height 36 --spp 4 --method $m --seed 1 -o /tmp/s.exr 2>&1 \
      | grep -E "executable" | sed -E "s|^.*render \(ris=(\w+), guiding=(\w+), training=(\w+).*executable 0[^:]*: |$b $m ris=\1 guiding=\2 training=\3: |" >> $O
  done
done

log "== host work $((SECONDS-t0))"
for round in 1 2; do
  for b in $(ls /tmp/host | sort); do
    for s in street bistro-night; do
      for m in guided guided-ris; do
        timeout 60 /tmp/host/$b --log info render scenes/$s.gltf $W --method $m --spp $SPP --seed 1 -o /tmp/g.exr 2>&1 \
          | grep -E "training iteration|training took|M samples/s" | sed "s|^|r$round $b $s $m: |" >> $O
      done
    done
  done
  log "round $round done $((SECONDS-t0))"
done
log "done $((SECONDS-t0))"
