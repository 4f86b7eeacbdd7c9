#!/usr/bin/env bash
# `loupe check --no-device` against naga-cli on a real corpus: every WGSL
# file of the wgpu repository at a pinned commit (naga's snapshot inputs,
# the examples, the tests), through bench/check.sh.
#
# Usage: bench/wgpu_corpus.sh [check.sh options]
# Env: WGPU_GIT (default https://github.com/gfx-rs/wgpu.git; a local clone
#      or mirror works), CORPUS (default target/bench-wgpu-corpus), and
#      check.sh's RUNS and WARMUP.
#
# Files are flattened to one folder (path separators become `__`), and
# MANIFEST.tsv records naga's own verdict on each (`ok` or `bad`: some of
# naga's inputs are meant to fail), which check.sh compares with loupe's.
set -euo pipefail
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$ROOT"

WGPU_GIT=${WGPU_GIT:-https://github.com/gfx-rs/wgpu.git}
WGPU_REV=64a61ee5c69569bbb3db03563997e88a229eba17 # 2024-10-23
export CORPUS=${CORPUS:-target/bench-wgpu-corpus}
NAGA=target/naga-cli/bin/naga
[[ -x $NAGA ]] || cargo install naga-cli --version 30.0.1 --locked --root target/naga-cli

if [[ ! -f $CORPUS/.rev ]] || [[ $(cat "$CORPUS/.rev") != "$WGPU_REV" ]]; then
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    git init -q "$tmp/wgpu"
    git -C "$tmp/wgpu" fetch -q --depth 1 "$WGPU_GIT" "$WGPU_REV"
    rm -rf "$CORPUS"
    mkdir -p "$CORPUS"
    printf 'file\tverdict\n' >"$CORPUS/MANIFEST.tsv"
    while IFS= read -r path; do
        name=${path//\//__}
        git -C "$tmp/wgpu" show "FETCH_HEAD:$path" >"$CORPUS/$name"
        if "$NAGA" "$CORPUS/$name" >/dev/null 2>&1; then verdict=ok; else verdict=bad; fi
        printf '%s\t%s\n' "$name" "$verdict" >>"$CORPUS/MANIFEST.tsv"
    done < <(git -C "$tmp/wgpu" ls-tree -r --name-only FETCH_HEAD | grep '\.wgsl$')
    echo "$WGPU_REV" >"$CORPUS/.rev"
fi

CORPUS_ORIGIN="the .wgsl files of gfx-rs/wgpu at ${WGPU_REV:0:10}" exec bench/check.sh "$@"
