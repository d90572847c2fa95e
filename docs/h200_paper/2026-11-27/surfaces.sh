#!/bin/bash
# GPU session 2026-11-27 (second session of the day), second call: kernel variants that
# keep one surface live across a trace instead of two, through --shader-dir on one
# binary (.gpu/after/2-head.xz), against its own kernels (embedded):
#   shadowfirst  without RIS the shadow ray is traced before the direction ray, so the
#                next vertex's surface is made after the vertex's last trace
#   twosites     shadowfirst with a trace_ray call site per ray kind
#   deferris     shadowfirst, and with RIS the next surface made after the shadow ray
#                (RIS reads the hit's emitter through a small SurfaceEmitter)
#   deferris2    deferris with a call site per ray kind
# The driver's register statistics of each kernel, then M samples/s on bistro-night at
# 1024x576, 256 spp, two alternated rounds. Variant shader directories in .gpu/var/<name>.
# Lines go to $OUT/surfaces.txt as they are made. W and SPP shrink it for a dry run;
# V (variant list) and NAME (output name) let split.sh reuse it.
set -u
for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
L=/tmp/lanterna_sv; xz -dc .gpu/after/2-head.xz > $L 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('.gpu/after/2-head.xz').read())" > $L; chmod +x $L
$L --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
O=$OUT/${NAME:-surfaces}.txt; W=${W:-"--width 1024 --height 576"}; SPP=${SPP:-256}; t0=$SECONDS
V=${V:-"embedded .gpu/var/shadowfirst .gpu/var/twosites .gpu/var/deferris .gpu/var/deferris2"}
log() { echo "$*" | tee -a $O; }
log "== kernel statistics $((SECONDS-t0))"
for v in $V; do
  sd=""; [ $v != embedded ] && sd="--shader-dir $v"
  for m in pt ris guided guided-ris; do
    timeout 60 $L --log debug render scenes/bistro-night.gltf --width 64 --height 36 --spp 4 --method $m --seed 1 $sd -o /tmp/s.exr 2>&1 \
      | grep -E "executable|rror" | sed -E "s|^.*render \(ris=(\w+), guiding=(\w+), training=(\w+).*executable 0[^:]*: |$v $m ris=\1 guiding=\2 training=\3: |" >> $O
  done
done
log "== speed $((SECONDS-t0))"
for round in 1 2; do
  for v in $V; do
    sd=""; [ $v != embedded ] && sd="--shader-dir $v"
    for m in pt ris guided guided-ris; do
      l=$(timeout 60 $L --log info render scenes/bistro-night.gltf $W --method $m --spp $SPP --seed 3 $sd -o /tmp/o.exr 2>&1 \
        | grep -E "M samples/s" | sed -E 's/^.* ([0-9]+ spp in [0-9.]+ s).*: ([0-9.]+ M samples\/s).*/\1 \2/')
      log "r$round $v $m $l"
    done
  done
  log "round $round done $((SECONDS-t0))"
done
log "done $((SECONDS-t0))"
