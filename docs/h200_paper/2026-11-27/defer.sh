#!/bin/bash
# GPU session 2026-11-27, third call: the next vertex's surface made after the shadow ray
# (shaders in .gpu/var/defer, through --shader-dir) against the build's own kernels
# (embedded), same binary (.gpu/host/1-after.xz): the driver's register statistics, then
# M samples/s on bistro-night and the street at 1024x576, 256 spp, two alternated rounds.
# Lines go to $OUT/defer.txt as they are made. W shrinks it for a dry run.
set -u
for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
L=/tmp/lanterna; xz -dc .gpu/host/1-after.xz > $L 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('.gpu/host/1-after.xz').read())" > $L; chmod +x $L
$L --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
O=$OUT/defer.txt
W=${W:-"--width 1024 --height 576"}
SPP=${SPP:-256}
t0=$SECONDS
log() { echo "$*" | tee -a $O; }
log "== kernel statistics $((SECONDS-t0))"
for v in embedded .gpu/var/defer; do
  sd=""; [ $v != embedded ] && sd="--shader-dir $v"
  for m in pt ris guided guided-ris; do
    timeout 60 $L --log debug render scenes/bistro-night.gltf --width 64 --height 36 --spp 4 --method $m --seed 1 $sd -o /tmp/s.exr 2>&1 \
      | grep -E "executable" | sed -E "s|^.*render \(ris=(\w+), guiding=(\w+), training=(\w+).*executable 0[^:]*: |$v $m ris=\1 guiding=\2 training=\3: |" >> $O
  done
done
log "== speed $((SECONDS-t0))"
for round in 1 2; do
  for s in bistro-night street; do
    for v in embedded .gpu/var/defer; do
      sd=""; [ $v != embedded ] && sd="--shader-dir $v"
      for m in pt ris guided guided-ris; do
        l=$(timeout 60 $L --log info render scenes/$s.gltf $W --method $m --spp $SPP --seed 3 $sd -o /tmp/o.exr 2>&1 | grep -E "M samples/s" | sed -E 's/^.* ([0-9]+ spp in [0-9.]+ s).*: ([0-9.]+ M samples\/s).*/\1 \2/')
        log "r$round $s $v $m $l"
      done
    done
  done
done
log "done $((SECONDS-t0))"
