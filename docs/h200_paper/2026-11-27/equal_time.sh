#!/bin/bash
# GPU session 2026-11-27 (fourth of the day): equal time on `bistro-night` at 1024x576 with
# longer budgets than the 2026-11-26 table (2 and 4 s): 4, 8 and 16 s of rendering, all four
# methods, current defaults (.gpu/ga/now.xz), seed 1, against a 16,384-spp `ris` reference
# (seed 777), as docs/h200_paper/run.sh made them. Reports go to $OUT/equal_time.tar.gz.
# W, RS and TT shrink it for a dry run on lavapipe.
set -u
[ -n "${NOGL:-}" ] || { for f in .gl/*.deb; do dpkg -x $f / 2>/dev/null; done; ldconfig >/dev/null 2>&1; }
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
L=/tmp/lga/now; [ -x $L ] || { mkdir -p /tmp/lga; xz -dc .gpu/ga/now.xz > $L; chmod +x $L; }
W=${W:-"--width 1024 --height 576"}; RS=${RS:-16384}; TT=${TT:-4,8,16}; t0=$SECONDS
R=/tmp/et; mkdir -p $R
snap() { tar czf $OUT/equal_time.tar.gz --exclude='*.png' --exclude='*.exr' --exclude='*.html' -C /tmp et; }
s=bistro-night
echo "== $s ref $((SECONDS-t0))" | tee -a $R/progress.txt
timeout 200 $L --log warn render scenes/$s.gltf $W --method ris --spp $RS --seed 777 -o /tmp/ref_$s.exr > $R/ref.log 2>&1 || { echo "ref failed"; tail -5 $R/ref.log; }
echo "== $s time $TT $((SECONDS-t0))" | tee -a $R/progress.txt
timeout 240 $L --log info compare scenes/$s.gltf $W --reference /tmp/ref_$s.exr --seed 1 --methods pt,ris,guided,guided-ris --time $TT --out-dir $R/$s-time > $R/$s-time.log 2>&1 || tail -3 $R/$s-time.log
snap
echo "done $((SECONDS-t0))" | tee -a $R/progress.txt
snap
