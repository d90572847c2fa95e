#!/bin/bash
# GPU session 2026-11-27 (second session of the day), third call: the work that traces no
# ray in an iteration of its own, through --shader-dir (.gpu/var/<name>), against the
# binary's own kernels (embedded); surfaces.sh's measurement, output split.txt:
#   splitris     RIS's light choice after the direction ray's hit in its own iteration
#   splitsample  the next vertex's sampling (direction, and NEE without RIS) in its own
#   splitboth    both
V="embedded .gpu/var/splitris .gpu/var/splitsample .gpu/var/splitboth" NAME=split \
  bash "$(dirname "$0")/surfaces.sh"
