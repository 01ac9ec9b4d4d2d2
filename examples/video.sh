#!/usr/bin/env sh
# The default box flown through along examples/camera_path.toml, as an MP4: bake once into a
# cache, then the path's 121 frames drawn from it and encoded in the process.
#   sh examples/video.sh [SIZE] [OUT.mp4]        (SIZE: even, default 512)
set -eu
cd "$(dirname "$0")/.."
size="${1:-512}"
out="${2:-fly.mp4}"
lobelight="${LOBELIGHT:-target/release/lobelight}"
[ -x "$lobelight" ] || cargo build --release
"$lobelight" render scenes/cornell.toml --width "$size" --height "$size" --spp 4 \
    --views examples/camera_path.toml --cache target/cornell.bake -o "$out"
