#!/bin/bash
# GPU session 2026-11-27 (second session of the day), fourth call: the scene's read-only
# arrays read through buffer references (device addresses in FrameParams) instead of
# bound storage buffers, a lavapipe speed-up, checked on the GPU: the build before
# (.gpu/bda/1-head.xz) and after (.gpu/bda/2-addresses.xz), the driver's register
# statistics, then M samples/s on bistro-night and the street at 1024x576, 256 spp, two
# alternated rounds. Lines go to $OUT/addresses.txt. W and SPP shrink it for a dry run.
set -u
for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
mkdir -p /tmp/lbda; for x in .gpu/bda/*.xz; do n=$(basename $x .xz); xz -dc $x > /tmp/lbda/$n 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('$x').read())" > /tmp/lbda/$n; chmod +x /tmp/lbda/$n; done
/tmp/lbda/1-head --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
O=$OUT/addresses.txt; W=${W:-"--width 1024 --height 576"}; SPP=${SPP:-256}; t0=$SECONDS
log() { echo "$*" | tee -a $O; }
log "== kernel statistics $((SECONDS-t0))"
for b in $(ls /tmp/lbda | sort); do
  for m in pt ris guided guided-ris; do
    timeout 60 /tmp/lbda/$b --log debug render scenes/bistro-night.gltf --width 64 --height 36 --spp 4 --method $m --seed 1 -o /tmp/s.exr 2>&1 \
      | grep -E "executable|rror" | sed -E "s|^.*render \(ris=(\w+), guiding=(\w+), training=(\w+).*executable 0[^:]*: |$b $m ris=\1 guiding=\2 training=\3: |" >> $O
  done
done
log "== speed $((SECONDS-t0))"
for round in 1 2; do
  for s in bistro-night street; do
    for b in $(ls /tmp/lbda | sort); do
      for m in pt ris guided guided-ris; do
        l=$(timeout 60 /tmp/lbda/$b --log info render scenes/$s.gltf $W --method $m --spp $SPP --seed 3 -o /tmp/o.exr 2>&1 \
          | grep -E "M samples/s" | sed -E 's/^.* ([0-9]+ spp in [0-9.]+ s).*: ([0-9.]+ M samples\/s).*/\1 \2/')
        log "r$round $s $b $m $l"
      done
    done
  done
  log "round $round done $((SECONDS-t0))"
done
log "done $((SECONDS-t0))"
