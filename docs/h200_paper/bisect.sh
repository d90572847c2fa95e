#!/bin/bash
# GPU speed of older builds against the current one, same machine, alternated rounds.
# Run from the repository root on the GPU machine: stripped builds xz-compressed as
# .gpu/bis/<order>-<commit>.xz (7-HEAD.xz the current one), the Vulkan loader's .deb
# files in .gl/; one line per render is appended to $OUT/bisect.txt.
set -u
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig >/dev/null 2>&1
[ -f /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json ] && export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
mkdir -p /tmp/b
for x in .gpu/bis/*.xz; do n=$(basename $x .xz); (xz -dc $x 2>/dev/null || python3 -c "import lzma,sys;sys.stdout.buffer.write(lzma.open('$x').read())") > /tmp/b/$n; chmod +x /tmp/b/$n; done
/tmp/b/7-HEAD --version >/dev/null 2>&1 || export LD_LIBRARY_PATH=$PWD/.gpu/lib
W=${W:-"--width 1024 --height 576"}
for round in ${ROUNDS:-1 2}; do
  for b in $(ls /tmp/b | sort); do
    for m in pt ris guided; do
      l=$(timeout 40 /tmp/b/$b --log info render scenes/bistro-night.gltf $W --method $m --spp 256 --seed 3 -o /tmp/o.exr 2>&1 | grep -E "M samples/s" | sed -E 's/^.* ([0-9]+ spp in [0-9.]+ s).*: ([0-9.]+ M samples\/s).*/\1 \2/')
      echo "r$round $b $m $l" | tee -a $OUT/bisect.txt
    done
  done
done
