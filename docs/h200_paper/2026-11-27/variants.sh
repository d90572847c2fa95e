#!/bin/bash
# GPU session 2026-11-27: kernel variants A/B'd through --shader-dir on one binary, the
# driver's register statistics of each kernel, the builds around the one-call-site
# change, and the guided methods' host work per training pass at the paper's size.
# Run from the repository root on the GPU machine: stripped builds xz-compressed as
# .gpu/bis/<order>-<commit>.xz (the current one as 9-HEAD.xz), variant shader
# directories under .gpu/var/<name>, the Vulkan loader's .deb files in .gl/. Every line
# goes to $OUT/variants.txt as it is made. W shrinks the renders for a dry run.
set -u
for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
mkdir -p /tmp/b
for x in .gpu/bis/*.xz; do n=$(basename $x .xz); xz -dc $x > /tmp/b/$n 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('$x').read())" > /tmp/b/$n; chmod +x /tmp/b/$n; done
L=/tmp/b/9-HEAD
$L --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
O=$OUT/variants.txt
W=${W:-"--width 1024 --height 576"}
SPP=${SPP:-256}
t0=$SECONDS
log() { echo "$*" | tee -a $O; }
rate() { grep -E "M samples/s" | sed -E 's/^.* ([0-9]+ spp in [0-9.]+ s).*: ([0-9.]+ M samples\/s).*/\1 \2/'; }

log "== kernel statistics $((SECONDS-t0))"
for v in embedded shaders_glsl $(ls .gpu/var 2>/dev/null | sed 's|^|.gpu/var/|'); do
  sd=""; [ $v != embedded ] && sd="--shader-dir $v"
  for m in pt ris guided guided-ris; do
    timeout 60 $L --log debug render scenes/bistro-night.gltf --width 64 --height 36 --spp 4 --method $m --seed 1 $sd -o /tmp/s.exr 2>&1 \
      | grep -E "pipeline .*(executable|created)" | sed "s|^|$v $m: |" >> $O
  done
done

log "== variants $((SECONDS-t0))"
for round in 1 2; do
  for v in embedded shaders_glsl $(ls .gpu/var 2>/dev/null | sed 's|^|.gpu/var/|'); do
    sd=""; [ $v != embedded ] && sd="--shader-dir $v"
    for m in pt ris guided; do
      l=$(timeout 60 $L --log info render scenes/bistro-night.gltf $W --method $m --spp $SPP --seed 3 $sd -o /tmp/o.exr 2>&1 | rate)
      log "r$round $v $m $l"
    done
  done
done

log "== builds $((SECONDS-t0))"
for round in 1 2; do
  for b in $(ls /tmp/b | sort); do
    for m in pt ris; do
      l=$(timeout 40 /tmp/b/$b --log info render scenes/bistro-night.gltf $W --method $m --spp $SPP --seed 3 -o /tmp/o.exr 2>&1 | rate)
      log "r$round $b $m $l"
    done
  done
done

log "== host work per training pass $((SECONDS-t0))"
for s in street bistro-night; do
  for m in guided guided-ris; do
    timeout 60 $L --log debug render scenes/$s.gltf $W --method $m --spp 1000 --seed 1 -o /tmp/g.exr 2>&1 \
      | grep -E "guiding iteration|M samples/s|training" | sed "s|^|$s $m: |" >> $O
  done
done
log "done $((SECONDS-t0))"
