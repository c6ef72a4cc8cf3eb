#!/usr/bin/env bash
# Rays per sample of Mitsuba 3's llvm_ad_rgb and of vkpt on the two scenes
# of benches/mitsuba_cornell.py (not run by CI): the same estimator traces
# the same number of extension rays per sample, so a difference means the
# two path tracers end paths differently. (This count found vkpt's Russian
# roulette starting a bounce after Mitsuba's, fixed in 8ce0c9e.)
#
# Mitsuba's rays are counted by benches/embree/count_rays.cpp, a preloaded
# library that counts the active lanes of its rtcIntersect16 and
# rtcOccluded16 calls (the 16-wide calls its kernels make with AVX-512;
# a machine without AVX-512 makes 8-wide calls, which it does not count).
# vkpt's come from its summary line.
#
#   bash benches/mitsuba_rays.sh            # 256x256, 16 spp
#   VKPT_RAYS_SPP=64 bash benches/mitsuba_rays.sh
#
# Needs target/mitsuba-venv (made by `python3 benches/mitsuba_cornell.py`),
# a C++ compiler and target/release/vkpt.
set -euo pipefail
cd "$(dirname "$0")/.."

source benches/mitsuba_venv.sh
out=target/mitsuba-rays
mkdir -p "$out"
c++ -O2 -std=c++17 -shared -fPIC -Wall -Wextra \
  -DEMBREE_LIB="\"$PWD/$mitsuba/libembree3.so\"" \
  benches/embree/count_rays.cpp -o "$out/libcount_rays.so" -ldl

spp=${VKPT_RAYS_SPP:-16}
for which in cornell spheres; do
  case $which in
    cornell) gltf=scenes/cornell-box.gltf ;;
    spheres) gltf=scenes/cornell-spheres.gltf ;;
  esac
  samples=$((256 * 256 * spp))
  # Mitsuba's whole render as its whole-process benchmark runs it.
  counted=$(LD_PRELOAD="$PWD/$out/libcount_rays.so" target/mitsuba-venv/bin/python -c "
import sys; sys.path.insert(0, 'benches')
import mitsuba_cornell as bench
bench.choose_libllvm()
bench.mitsuba_once('llvm_ad_rgb', '$which', $spp, '$out/$which-mitsuba.exr')")
  read -r ext shadow < <(echo "$counted" | sed -n 's/^mitsuba rays: \([0-9]*\) extension, \([0-9]*\) shadow$/\1 \2/p')
  vkpt=$(target/release/vkpt "$gltf" --device cpu --width 256 --spp "$spp" -o "$out/$which-vkpt.exr" 2>&1 |
    sed -n 's/.*(\([0-9.]*\) \([kM]\)extension + \([0-9.]*\) \([kM]\)shadow rays).*/\1 \2 \3 \4/p')
  read -r ve vu vs vsu <<< "$vkpt"
  scale() { case $2 in M) echo "$1 * 1000000" | bc ;; k) echo "$1 * 1000" | bc ;; esac; }
  printf '%-8s %d samples | Mitsuba llvm_ad_rgb: %.3f extension + %.3f shadow rays per sample | vkpt: %.3f + %.3f\n' \
    "$which" "$samples" \
    "$(echo "$ext / $samples" | bc -l)" "$(echo "$shadow / $samples" | bc -l)" \
    "$(echo "$(scale "$ve" "$vu") / $samples" | bc -l)" "$(echo "$(scale "$vs" "$vsu") / $samples" | bc -l)"
done
