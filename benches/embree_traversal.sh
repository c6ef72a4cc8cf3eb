#!/usr/bin/env bash
# vkpt's CPU traversal against Embree's, on the same triangles and rays
# (not run by CI).
#
# Mitsuba 3's llvm_ad_rgb, the renderer issue 13 measures vkpt against,
# traces with Embree 3: one rtcIntersectN per packet of its vectorized
# kernel's lanes (N = 16 with AVX-512, 8 with AVX2). This script asks how
# much of its lead is traversal: `cargo bench --bench traversal` writes its
# ray sets (primary rays, and diffuse bounces from their hits) and the CPU
# reference's hits, and benches/embree/trace_embree.cpp traces them with the
# Embree that Mitsuba's wheel ships, single rays and packets of 4, 8 and 16,
# on as many threads as the CPU reference uses.
#
#   bash benches/embree_traversal.sh            # cornell, helmet, spheres
#   VKPT_TRAV_SCENES=cornell VKPT_TRAV_RUNS=7 bash benches/embree_traversal.sh
#
# Needs target/mitsuba-venv (made by `python3 benches/mitsuba_cornell.py`)
# and a C++ compiler (Mitsuba builds Embree's API into a C++ namespace).
set -euo pipefail
cd "$(dirname "$0")/.."

source benches/mitsuba_venv.sh
out=target/embree-traversal
mkdir -p "$out"
c++ -O2 -std=c++17 -Wall -Wextra -I "$mitsuba/include" \
  benches/embree/trace_embree.cpp -o "$out/trace_embree" \
  -L "$mitsuba" -l:libembree3.so -Wl,-rpath,"$PWD/$mitsuba" -lpthread -lm

runs=${VKPT_TRAV_RUNS:-5}
# Only this run's ray sets: a scene left out now must not be traced from an
# earlier run's files.
rm -f "$out"/*.tris "$out"/*.rays "$out"/*.hits
VKPT_TRAV_DUMP="$out" VKPT_TRAV_RUNS=$runs cargo bench --bench traversal
threads=$(nproc)
for tris in "$out"/*.tris; do
  label=$(basename "$tris" .tris)
  for set in primary incoherent; do
    echo "$label $set ($threads threads):"
    "$out/trace_embree" "$tris" "$out/$label-$set.rays" "$out/$label-$set.hits" "$runs" "$threads"
  done
done
