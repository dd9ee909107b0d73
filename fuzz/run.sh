#!/usr/bin/env bash
# fuzz/run.sh [SECONDS] [--replay] — run every fuzz target (make fuzz) for
# SECONDS each (default 60), on a corpus seeded from tests/data and small
# generated SPD scenes (build-fuzz/corpus-TARGET, kept between runs).
# --replay only runs the seeds once each (deterministic; what CI does).
# A finding is written to build-fuzz/finding-TARGET-* and the run stops with
# exit status 1; replay one with build-fuzz/fuzz_TARGET FILE.
# The whole script is one block, read before it runs, so that editing this
# file during a long run cannot change what the run does.
{
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=60 replay=0
for a in "$@"; do
    case "$a" in
    --replay) replay=1 ;;
    *) seconds=$a ;;
    esac
done
make -s -j"$(nproc 2>/dev/null || echo 2)" fuzz >/dev/null
make -s build/bspray >/dev/null

seeds=build-fuzz/seeds
rm -rf "$seeds" && mkdir -p "$seeds"
# An input is one byte choosing the reader (value mod 3: NFF, OBJ, PLY) and
# the structure (value / 3 mod 8: sah, kaplan, sah-per, grid, octree, bvh,
# bvh4, bvh8; value / 24 mod 2: for the octree centre or cost split, for the
# grid uniform or recursive), then the file.
seed() { # FORMAT FILE NAME: ten seeds, one per structure (k 12: the octree cut
    # by cost; k 11: the recursive grid)
    for k in 0 1 2 3 4 5 6 7 11 12; do
        { printf "\\$(printf '%03o' $((k * 3 + $1)))"; cat "$2"; } >"$seeds/$3-$k"
    done
}
i=0
for f in tests/data/nff_good/*.nff; do seed 0 "$f" "nff$((i++))"; done
for f in tests/data/obj/*.obj; do seed 1 "$f" "obj$((i++))"; done
for f in tests/data/ply/*.ply; do seed 2 "$f" "ply$((i++))"; done
for s in balls:1 tetra:2 gears:1 rings:1 tree:3 shells:1 sample:1 jacks:1; do
    ./build/bspray gen "${s%%:*}" -s "${s##*:}" -o "build-fuzz/gen.nff"
    seed 0 build-fuzz/gen.nff "spd-${s%%:*}"
done
rm -f build-fuzz/gen.nff
# the tree-file target's seeds: trees of its scene, spd:balls:1
trees=build-fuzz/seeds-tree_file
rm -rf "$trees" && mkdir -p "$trees"
./build/bspray build spd:balls:1 -o "$trees/sah.kdt" >/dev/null
./build/bspray build spd:balls:1 --accel kaplan -o "$trees/kaplan.kdt" >/dev/null
./build/bspray build spd:balls:1 --mailbox off --max-depth 6 -o "$trees/shallow.kdt" >/dev/null

status=0
for t in build-fuzz/fuzz_*; do
    name=${t#build-fuzz/fuzz_}
    corpus=build-fuzz/corpus-$name
    mkdir -p "$corpus"
    seeds=build-fuzz/seeds
    [ -d "build-fuzz/seeds-$name" ] && seeds=build-fuzz/seeds-$name
    if [ "$replay" = 1 ]; then
        echo "== $name: the $(ls "$seeds" | wc -l) seeds once each"
        args=(-runs=0 "$seeds")
    else
        echo "== $name: $seconds s"
        args=(-max_total_time="$seconds" -max_len=8192 -timeout=30 -rss_limit_mb=4096 "$corpus" "$seeds")
    fi
    if ! "$t" "${args[@]}" -artifact_prefix="build-fuzz/finding-$name-" >"build-fuzz/$name.log" 2>&1; then
        echo "$name: a finding (build-fuzz/$name.log):"
        grep -E -m 5 "ERROR|differs|says|status|pixel|ray class|refused|Test unit" "build-fuzz/$name.log" || tail -5 "build-fuzz/$name.log"
        status=1
    else
        grep -E "^Done|^#[0-9]+ +DONE" "build-fuzz/$name.log" | tail -1 || true
    fi
done
rm -f /tmp/bspray-fuzz-tree-*.kdt # fuzz_tree_file's file (libFuzzer ends without atexit)
exit $status
}
