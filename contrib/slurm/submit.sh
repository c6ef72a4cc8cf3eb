#!/usr/bin/env bash
# Submits a render split over a Slurm job array, and the merge that waits
# for it.
#
#   contrib/slurm/submit.sh TASKS SCENE.gltf SPP OUT.exr [vkpt options...]
#
# e.g. contrib/slurm/submit.sh 16 scene.gltf 4096 frame.exr --width 3840 --height 2160
#
# Parts go to a folder named after OUT.exr (frame.parts/part-<i>.exr; it
# should not hold parts of an earlier run); the jobs log to the current
# folder. Prints what it submitted on stderr and the two job ids (array,
# merge) on stdout. Extra sbatch options (partition, account,
# --gres=gpu:1) can be given in SBATCH_EXTRA.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)

if [ $# -lt 4 ]; then
  echo "usage: $0 TASKS SCENE.gltf SPP OUT.exr [vkpt options...]" >&2
  exit 2
fi
tasks=$1 scene=$2 spp=$3 output=$4
shift 4
if ! [ "$tasks" -ge 1 ] 2>/dev/null || ! [ "$spp" -ge "$tasks" ] 2>/dev/null; then
  echo "$0: TASKS must be at least 1 and SPP at least TASKS (got $tasks, $spp)" >&2
  exit 2
fi
parts="${output%.exr}.parts"
# shellcheck disable=SC2086 # SBATCH_EXTRA is a list of options
array=$(sbatch --parsable ${SBATCH_EXTRA:-} --array="0-$((tasks - 1))" \
  "$here/render-part.sbatch" "$scene" "$parts" "$spp" "$@")
array=${array%%;*}
# shellcheck disable=SC2086
merge=$(sbatch --parsable ${SBATCH_EXTRA:-} --dependency="afterok:$array" \
  "$here/merge.sbatch" "$parts" "$output" "$spp")
merge=${merge%%;*}
echo "render array: job $array ($tasks tasks), merge: job $merge (runs once all succeed)" >&2
echo "$array $merge"
