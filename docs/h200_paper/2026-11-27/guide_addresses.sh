#!/bin/bash
# GPU session 2026-11-27 (run in the fourth session of the day): the SD-tree's arrays read
# through device addresses (push constants) where the scene's are, and `--scene-arrays`.
# Checks that GPUs' default (bound buffers) did not move with the larger push constants and
# the accessors (.gpu/ga/before.xz: ced2456; .gpu/ga/now.xz: 82fb504, which also has the
# shadow-ray stop of b4e6465), and measures the
# addresses forced on (`--scene-arrays addresses`, now the SD-tree's arrays too): the
# driver's register statistics, then M samples/s on bistro-night and the street at
# 1024x576, 256 spp, two alternated rounds. Lines go to $OUT/guide_addresses.txt.
set -u
[ -n "${NOGL:-}" ] || { for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1; }
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
mkdir -p /tmp/lga; for x in .gpu/ga/*.xz; do n=$(basename $x .xz); xz -dc $x > /tmp/lga/$n 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('$x').read())" > /tmp/lga/$n; chmod +x /tmp/lga/$n; done
/tmp/lga/now --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
O=$OUT/guide_addresses.txt; W=${W:-"--width 1024 --height 576"}; SPP=${SPP:-256}; t0=$SECONDS
log() { echo "$*" | tee -a $O; }
# configuration: binary and extra flags
configs=("before|" "now|" "now|--scene-arrays addresses")
log "== kernel statistics $((SECONDS-t0))"
for c in "${configs[@]}"; do
  b=${c%%|*}; f=${c#*|}
  for m in pt ris guided guided-ris; do
    timeout 60 /tmp/lga/$b --log debug render scenes/bistro-night.gltf --width 64 --height 36 --spp 4 --method $m --seed 1 $f -o /tmp/s.exr 2>&1 \
      | grep -E "executable|rror" | sed -E "s|^.*render \(ris=(\w+), guiding=(\w+), training=(\w+).*executable 0[^:]*: |$b$f $m ris=\1 guiding=\2 training=\3: |" >> $O
  done
done
log "== speed $((SECONDS-t0))"
for round in 1 2; do
  for s in bistro-night street; do
    for c in "${configs[@]}"; do
      b=${c%%|*}; f=${c#*|}
      for m in pt ris guided guided-ris; do
        l=$(timeout 60 /tmp/lga/$b --log info render scenes/$s.gltf $W --method $m --spp $SPP --seed 3 $f -o /tmp/o.exr 2>&1 \
          | grep -E "M samples/s" | sed -E 's/^.* ([0-9]+ spp in [0-9.]+ s).*: ([0-9.]+ M samples\/s).*/\1 \2/')
        log "r$round $s $b${f:+ $f} $m $l"
      done
    done
  done
  log "round $round done $((SECONDS-t0))"
done
log "done $((SECONDS-t0))"
