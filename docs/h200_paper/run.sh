#!/bin/bash
# Paper-scale study on the lent GPU: current defaults, learned light mix for guided-ris,
# guide history 1; bistro-night and street at 1024x576, 16,384-spp ris references.
# Run from the repository root on the GPU machine, with the Vulkan loader's .deb files in
# .gl/ and a stripped release build at .gpu/lanterna (libstdc++ in .gpu/lib if that
# machine lacks it); results go to $OUT/res.tar.gz after every step. W, RS, SP and TT
# (size, reference spp, spp list, time list) shrink it for a dry run on lavapipe.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
L=$PWD/.gpu/lanterna
$L --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
R=/tmp/res; mkdir -p $R
snap() { tar czf $OUT/res.tar.gz --exclude='*-2/grid.png' --exclude='*lmix*/grid.png' --exclude='*hist*/grid.png' -C /tmp res; }
{ nvidia-smi -L; $L info; } > $R/info.txt 2>&1; cat $R/info.txt | head -20
W=${W:-"--width 1024 --height 576"}; RS=${RS:-16384}; SP=${SP:-256,1000}; TT=${TT:-2,4}
t0=$SECONDS
for s in bistro-night street; do
  echo "== $s ref $((SECONDS-t0))"
  timeout 150 $L --log warn reference scenes/$s.gltf $W --method ris --spp $RS --seed 777 -o /tmp/ref_$s.exr > $R/ref_$s.log 2>&1 || { echo "ref $s failed"; tail -5 $R/ref_$s.log; }
  [ -f /tmp/ref_$s.exr ] || { $L --log warn render scenes/$s.gltf $W --method ris --spp $RS --seed 777 -o /tmp/ref_$s.exr > $R/ref_$s.log 2>&1; }
  C="$L --log warn compare scenes/$s.gltf $W --reference /tmp/ref_$s.exr"
  for seed in 1 2; do
    echo "== $s seed $seed defaults $((SECONDS-t0))"
    T=""; [ $seed = 1 ] && T="--time $TT"
    timeout 120 $C --seed $seed --methods pt,ris,guided,guided-ris --spp $SP $T --out-dir $R/$s-def-$seed > $R/$s-def-$seed.log 2>&1 || tail -3 $R/$s-def-$seed.log
    snap
    echo "== $s seed $seed learned $((SECONDS-t0))"
    timeout 60 $C --seed $seed --methods guided-ris --light-mix learned --spp $SP --out-dir $R/$s-lmix-$seed > $R/$s-lmix-$seed.log 2>&1 || tail -3 $R/$s-lmix-$seed.log
    echo "== $s seed $seed history $((SECONDS-t0))"
    timeout 60 $C --seed $seed --methods guided,guided-ris --guide-history 1 --spp $SP --out-dir $R/$s-hist-$seed > $R/$s-hist-$seed.log 2>&1 || tail -3 $R/$s-hist-$seed.log
    snap
  done
done
echo "done $((SECONDS-t0))"
