#!/bin/bash
# GPU session 2026-11-28: the defaults of 2026-11-28 at the paper's scale. Since the last
# GPU runs the BSDF selection is learned from each pass's second-moment estimate
# (`--selection-learner variance`, chosen on lavapipe at 80x45..64x64) and a time budget's
# last training pass fills the training time. Both scenes at 1024x576, max depth 4,
# 16,384-spp `ris` references (seed 777): all four methods at 1,000 spp and at 4 s (seed 1),
# then `guided` and `guided-ris` with Adam (`--selection-learner kl-adam`) at 1,000 spp,
# then, while time is left, seed 2 of both learners. Expects the loader's .deb files in .gl/
# and a stripped, xz-compressed release build of HEAD at .gpu/now.xz. Reports (csv, json,
# logs) go to $OUT/r28.tar.gz after every step. W, RS, SP, TT and NOGL=1 shrink it for a
# dry run on lavapipe.
set -u
[ -n "${NOGL:-}" ] || { for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1; }
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
L=/tmp/l28/lanterna; mkdir -p /tmp/l28; xz -dc .gpu/now.xz > $L; chmod +x $L
W=${W:-"--width 1024 --height 576"}; RS=${RS:-16384}; SP=${SP:-1000}; TT=${TT:-4}
LIMIT=${LIMIT:-400}; t0=$SECONDS
R=/tmp/r28; mkdir -p $R
snap() { tar czf $OUT/r28.tar.gz --exclude='*.png' --exclude='*.exr' --exclude='*.html' -C /tmp r28; }
log() { echo "== $* $((SECONDS-t0))" | tee -a $R/progress.txt; }
{ nvidia-smi -L 2>&1; $L --version; $L info; } > $R/info.txt 2>&1; head -5 $R/info.txt
for s in street bistro-night; do
  C="$L --log info compare scenes/$s.gltf $W --reference /tmp/ref_$s.exr"
  log "$s ref"
  timeout 150 $L --log info render scenes/$s.gltf $W --method ris --spp $RS --seed 777 -o /tmp/ref_$s.exr > $R/ref_$s.log 2>&1 || { echo "ref $s failed"; tail -5 $R/ref_$s.log; continue; }
  log "$s defaults"
  timeout 150 $C --seed 1 --methods pt,ris,guided,guided-ris --spp $SP --time $TT --out-dir $R/$s-def-1 > $R/$s-def-1.log 2>&1 || tail -3 $R/$s-def-1.log
  snap
  log "$s kl-adam"
  timeout 60 $C --seed 1 --methods guided,guided-ris --selection-learner kl-adam --spp $SP --out-dir $R/$s-kl-1 > $R/$s-kl-1.log 2>&1 || tail -3 $R/$s-kl-1.log
  snap
done
# The Lambertian shortcut (constant BSDF_KERNEL, since 2026-11-28's later session) against
# the general BSDF: compiled in alone on the all-Lambertian street-matte, a branch per
# surface on the street; samples/s of pt and guided-ris, alternated.
for r in 1 2; do
  for s in street-matte street; do
    for m in pt guided-ris; do
      for g in "" --general-bsdf; do
        [ $((SECONDS-t0)) -lt $LIMIT ] || break 4
        log "$s lambertian $m ${g:-default} round $r"
        timeout 60 $L --log info render scenes/$s.gltf $W --method $m --spp 256 --seed 1 $g -o /tmp/sm.exr 2>&1 | grep -E "BSDF|spp in" >> $R/lambertian.txt
      done
    done
  done
done
snap
# World-space light reuse (--light-reuse world, opt-in since 2026-11-28's third session):
# ris and guided-ris with it, at the same spp and time as the defaults above. On lavapipe
# its one dispatch per sample cost 17-43 %; a GPU's dispatches should cost far less.
for s in street bistro-night; do
  [ -f /tmp/ref_$s.exr ] || continue
  [ $((SECONDS-t0)) -lt $LIMIT ] || break
  log "$s light reuse"
  timeout 90 $L --log info compare scenes/$s.gltf $W --reference /tmp/ref_$s.exr --seed 1 --methods ris,guided-ris --light-reuse world --spp $SP --time $TT --out-dir $R/$s-reuse-1 > $R/$s-reuse-1.log 2>&1 || tail -3 $R/$s-reuse-1.log
  snap
done
for s in street bistro-night; do
  [ -f /tmp/ref_$s.exr ] || continue
  C="$L --log info compare scenes/$s.gltf $W --reference /tmp/ref_$s.exr"
  for l in variance kl-adam; do
    [ $((SECONDS-t0)) -lt $LIMIT ] || { log "stop before $s $l seed 2"; break 2; }
    log "$s $l seed 2"
    timeout 60 $C --seed 2 --methods guided,guided-ris --selection-learner $l --spp $SP --out-dir $R/$s-$l-2 > $R/$s-$l-2.log 2>&1 || tail -3 $R/$s-$l-2.log
    snap
  done
done
log done
snap
