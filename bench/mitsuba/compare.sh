#!/bin/sh
# loupe's path tracer against Mitsuba 3 on the same scenes, the same CPU,
# interleaved scene by scene so a change in the machine's load hits both:
# prints paths per second of each and their ratio. Needs the install in
# README.md beside this and a release build:
#   cargo build --release -p loupe -p loupe-tests --bins
set -eu
cd "$(dirname "$0")/../.."
PY=${MITSUBA_PYTHON:-/work/venv-mitsuba/bin/python}
export DRJIT_LIBLLVM_PATH=${DRJIT_LIBLLVM_PATH:-/usr/lib/x86_64-linux-gnu/libLLVM-19.so}
BOUNCES=${BOUNCES:-3}
for entry in minimal:256:3 showcase:128:3 volume:256:2; do
  scene=${entry%%:*}; rest=${entry#*:}; spp=${rest%%:*}; frames=${rest#*:}
  out=/tmp/loupe-mitsuba/$scene
  target/release/bench-path-export "scenes/$scene.toml" "$out" >/dev/null
  loupe=$(target/release/loupe bench "scenes/$scene.toml" --size 640x360 --frames "$frames" --renderer path --bounces "$BOUNCES" 2>/dev/null |
    sed -n 's/.*, \([0-9.]*\) M paths\/s by the whole frame.*/\1/p')
  mitsuba=$("$PY" bench/mitsuba/paths.py "$out" --spp "$spp" --bounces "$BOUNCES" --threads 2 --runs 1 |
    sed -n 's/.*"paths_per_second": \([0-9.e+]*\).*/\1/p')
  echo "$scene: loupe $loupe M paths/s, mitsuba $mitsuba paths/s" |
    awk -v l="$loupe" -v m="$mitsuba" '{ printf "%s  (mitsuba / loupe = %.1f)\n", $0, m / 1e6 / l }'
done
