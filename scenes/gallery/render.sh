#!/usr/bin/env bash
# The seeds' experiments (shared/seeds: the lecture and the student report)
# rendered with vkpt's bundled scenes into small PNGs beside this script,
# for the gallery (README and docs/user-guide.md, "Gallery"). One command,
# from the repository root:
#
#     scenes/gallery/render.sh            # VKPT=path/to/vkpt to choose the binary
#
# Every image is 160 px wide on the CPU back end (--device cpu: the same
# paths as the Vulkan kernels), so the run takes about a minute on two cores.
set -euo pipefail
cd "$(dirname "$0")/../.."
out=scenes/gallery
vkpt=${VKPT:-target/release/vkpt}
[ -x "$vkpt" ] || cargo build --release --quiet --bin vkpt
cargo build --release --quiet --example photometric_stereo
r() { local name=$1; shift; echo "$name"; "$vkpt" "$@" --device cpu -q --width 160 -o "$out/$name.png" >/dev/null; }

# f-number series at a fixed focus: depth of field grows and exposure falls
# (the PNG's exposure follows EV100 from shutter, ISO and f-number).
for n in 1.4 4 16; do
  r "fstop-$n" scenes/depth-of-field.gltf --spp 64 --fstop "$n" --shutter 1 --iso 400
done
# Aperture blades: a round aperture against six blades (bokeh shape).
r bokeh-round scenes/depth-of-field.gltf --spp 96 --blades 0
r bokeh-hexagon scenes/depth-of-field.gltf --spp 96 --blades 6
# A mirror sphere in an environment, with depth of field.
r mirror-sphere-dof scenes/env-sky.gltf --spp 64 --fstop 2 --focal-length 0.05 --focus-distance 3
# Glass (IOR 1.5), an air bubble in glass (IOR below 1), mirror, Phong,
# rough metal and plastic, in the Cornell box.
r materials scenes/materials-showcase.gltf --spp 128
# Ambient occlusion: the box under a uniform white environment, direct light
# only, so corners and contacts darken as less of the sky reaches them.
r ambient-occlusion scenes/cornell-box.gltf --spp 64 --background 1,1,1 --max-depth 2
# Textures: bilinear (the floor's checker) and nearest (the wall's letter)
# filtering, wrap modes, a normal map and an alpha cutout.
r textures scenes/textured.gltf --spp 64
# 64 against 128 samples per pixel.
r cornell-64spp scenes/cornell-box.gltf --spp 64
r cornell-128spp scenes/cornell-box.gltf --spp 128
# The Bayer sensor: the raw RGGB mosaic and its demosaic (Malvar-He-Cutler).
r sensor-demosaic scenes/cornell-box.gltf --spp 64 --sensor bayer --raw-mosaic "$out/sensor-mosaic.png"
# Animation with motion blur: four frames (0.25 s apart) of the STEP,
# LINEAR, CUBICSPLINE and turning cubes, each exposed for 0.2 s.
echo animation
"$vkpt" scenes/animated/interpolation-test.gltf --device cpu -q --width 160 --spp 64 \
    --frames 0..4 --fps 4 --shutter 0.2 -o "$out/animation-%d.png" >/dev/null
# The two ways of blurring at 4 spp: a time per path (noise) against four
# host time steps (four ghost copies of the moving square).
for m in per-path time-steps; do
    "$vkpt" scenes/animated/moving-square.gltf --device cpu -q --width 160 --spp 4 \
        --shutter 0.25 --motion-blur $m -o "$out/blur-$m-4spp.png" >/dev/null
done
# Photometric stereo: the sphere's true normals, the recovered ones and the
# recovered albedo (examples/photometric_stereo.rs).
echo photometric-stereo
target/release/examples/photometric_stereo 160 4 "$out" >/dev/null
