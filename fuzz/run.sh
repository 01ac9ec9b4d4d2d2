#!/bin/sh
# Fuzzes one target from its kept corpus: `fuzz/run.sh TARGET [SECONDS]` (default 180; the
# targets: ply obj text las e57 scene views). New inputs go to fuzz/work/TARGET; at the end
# those that add coverage are merged into the corpus and its archive, and any crash is left in
# fuzz/artifacts/TARGET for a test in tests/fuzz_crashes.rs. Needs a nightly toolchain and
# cargo-fuzz (`cargo install cargo-fuzz`).
set -e
cd "$(dirname "$0")"
target=$1
seconds=${2:-180}
mkdir -p "corpus/$target" "work/$target"
tar -xzf "corpus/$target.tar.gz" -C corpus
cargo +nightly fuzz run -s none -O "$target" "work/$target" "corpus/$target" -- \
    -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10
cargo +nightly fuzz run -s none -O "$target" "corpus/$target" "work/$target" -- -merge=1
tar -czf "corpus/$target.tar.gz" -C corpus "$target"
