#!/usr/bin/env bash
# Renders the default scene every way `render` can with two builds of lobelight and compares
# the files byte for byte: a refactor that must change no image runs this with the build
# before and the build after. Both engines: the CPU mirror (the default without a GPU) and
# the adapter (--gpu; lavapipe will do).
#   benches/same-images.sh BEFORE_BINARY AFTER_BINARY [OUT_DIR]
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 BEFORE AFTER [OUT_DIR]" >&2; exit 2; }
cd "$(dirname "$0")/.."
out=${3:-$(mktemp -d)}
mkdir -p "$out"
S=scenes/cornell.toml
A=(--width 96 --height 96 --photons 60000)
printf '[orbit]\nframes = 4\n' > "$out/views.toml"
run() {
    local bin=$1 o=$2
    mkdir -p "$o"
    "$bin" render $S -o "$o/lobes.png" "${A[@]}"
    "$bin" render $S -o "$o/lobes.exr" "${A[@]}" --spp 4
    "$bin" render $S -o "$o/lobes0.png" "${A[@]}" --spp 0 --object-ids "$o/ids.png"
    "$bin" render $S -o "$o/ref.png" "${A[@]}" --method reference
    "$bin" render $S -o "$o/path.exr" "${A[@]}" --method path --spp 4
    "$bin" render $S -o "$o/photons.png" "${A[@]}" --method photons
    "$bin" render $S -o "$o/cached.png" "${A[@]}" --cache "$o/bake.cache"
    "$bin" render $S -o "$o/cached2.png" "${A[@]}" --cache "$o/bake.cache"
    "$bin" render $S -o "$o/v_#.png" "${A[@]}" --spp 1 --views "$out/views.toml" --shard 1/2
    "$bin" render $S -o "$o/g.png" "${A[@]}" --gpu --spp 2
    "$bin" render $S -o "$o/g0.exr" "${A[@]}" --gpu --spp 0
    "$bin" render $S -o "$o/gref.exr" "${A[@]}" --gpu --method reference
    "$bin" render $S -o "$o/gpath.exr" "${A[@]}" --gpu --method path --spp 2
    "$bin" render $S -o "$o/gphotons.png" "${A[@]}" --gpu --method photons
    "$bin" render $S -o "$o/gv_#.png" "${A[@]}" --gpu --spp 0 --views "$out/views.toml"
}
run "$1" "$out/before" 2>/dev/null
run "$2" "$out/after" 2>/dev/null
same=0 differ=0
for f in "$out/before"/*; do
    name=$(basename "$f")
    if cmp -s "$f" "$out/after/$name"; then same=$((same + 1)); else differ=$((differ + 1)); echo "differs: $name"; fi
done
echo "$same files identical, $differ differ ($out)"
[ "$differ" = 0 ]
