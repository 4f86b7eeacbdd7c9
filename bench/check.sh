#!/usr/bin/env bash
# Benchmark `loupe check --no-device` against naga's own CLI (naga-cli) on the
# same generated WGSL corpus, and print a markdown table for docs/benchmarks.md.
#
#   (a) loupe check --no-device --format json CORPUS   one process, whole dir
#   (b) naga FILE, once per file                        one process per file
#   (c) naga --bulk-validate CORPUS/*.wgsl              one process, all files
#
# Reported: the median wall time of each, and the ratios (b)/(a) and (c)/(a);
# above 1.00x means loupe is faster. The goal is (c)/(a) > 1 on the same
# machine: naga's bulk mode is the honest baseline, since it pays process
# start-up once, exactly like loupe.
#
# Usage: bench/check.sh [--naga-only] [--no-build]
#   --naga-only  time only (b) and (c) (e.g. before the loupe binary exists)
#   --no-build   use the existing target/release/loupe, don't run cargo
# Env: CORPUS (default target/bench-corpus), CORPUS_ORIGIN (a corpus made
#      elsewhere, with its MANIFEST.tsv: not regenerated; its description),
#      RUNS (default 10), WARMUP (1),
#      NO_HYPERFINE=1 to use the plain bash timing loop even if hyperfine exists.
#
# Invalid files are part of the corpus on purpose, so every timed command
# exits non-zero; that is expected and must not abort the run under
# `set -e` (hence hyperfine -i, and `|| true` on every direct invocation).
set -euo pipefail

SELF=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/$(basename "${BASH_SOURCE[0]}")
ROOT=$(dirname "$(dirname "$SELF")")
cd "$ROOT"

CORPUS=${CORPUS:-target/bench-corpus}
RUNS=${RUNS:-10}
WARMUP=${WARMUP:-1}
# naga-cli pinned to the naga the workspace depends on, so both sides run the
# same parser and validator version and the comparison measures the tools,
# not naga releases. Installed under target/ so it is never committed.
NAGA_VERSION=30.0.1
NAGA_ROOT=target/naga-cli
NAGA=$NAGA_ROOT/bin/naga
LOUPE=target/release/loupe
RESULTS=target/bench-results
NAGA_ONLY=0
BUILD=1

for arg in "$@"; do
    case $arg in
        --naga-only) NAGA_ONLY=1 ;;
        --no-build) BUILD=0 ;;
        -h | --help) sed -n '2,22p' "$SELF" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "unknown argument: $arg" >&2; exit 2 ;;
    esac
done

log() { printf '==> %s\n' "$*" >&2; }

# --- loupe ------------------------------------------------------------------
if [[ $NAGA_ONLY == 0 ]]; then
    if [[ $BUILD == 1 ]]; then
        log "cargo build --release -p loupe"
        cargo build --release -p loupe
    fi
    [[ -x $LOUPE ]] || { echo "missing $LOUPE (build it, or use --naga-only)" >&2; exit 1; }
fi

# --- naga-cli ---------------------------------------------------------------
if [[ ! -x $NAGA ]] || [[ $("$NAGA" --version 2>/dev/null) != "$NAGA_VERSION" ]]; then
    log "installing naga-cli $NAGA_VERSION into $NAGA_ROOT (a few minutes)"
    cargo install naga-cli --version "$NAGA_VERSION" --locked --root "$NAGA_ROOT"
fi

# --- corpus -----------------------------------------------------------------
# Regenerate when missing or when gen.py changed since (the stamp is gen.py's
# sha256); generation is deterministic, so this never changes a current one.
# A fresh corpus is verified against naga: ok_* validate, bad_* are rejected.
# CORPUS_ORIGIN names a corpus made elsewhere (bench/wgpu_corpus.sh makes
# one of wgpu's own shaders, with its MANIFEST.tsv): it is used as it is.
want_stamp=$(sha256sum bench/corpus/gen.py | cut -d' ' -f1)
if [[ -n ${CORPUS_ORIGIN:-} ]]; then
    [[ -f $CORPUS/MANIFEST.tsv ]] || { echo "$CORPUS has no MANIFEST.tsv" >&2; exit 1; }
elif [[ ! -f $CORPUS/.gen-stamp ]] || [[ $(cat "$CORPUS/.gen-stamp") != "$want_stamp" ]]; then
    log "generating corpus in $CORPUS"
    python3 bench/corpus/gen.py "$CORPUS" --verify "$NAGA"
fi

shopt -s nullglob
files=("$CORPUS"/*.wgsl)
shopt -u nullglob
(( ${#files[@]} > 0 )) || { echo "no .wgsl files in $CORPUS" >&2; exit 1; }
n_bad=$(awk -F'\t' 'NR > 1 && $2 == "bad"' "$CORPUS/MANIFEST.tsv" | wc -l)
n_lines=$(cat "${files[@]}" | wc -l)
n_bytes=$(cat "${files[@]}" | wc -c)

# --- sanity: loupe must reject exactly the files naga rejects -----------------
# A fast checker that skips work is not faster. Compare loupe's verdicts with
# the manifest (naga's verdicts) before timing. This only warns: the JSON
# schema belongs to loupe, and a mismatch is a finding, not a reason to stop.
mkdir -p "$RESULTS"
if [[ $NAGA_ONLY == 0 ]]; then
    rc=0
    "$LOUPE" check --no-device --format json "$CORPUS" >"$RESULTS/loupe.json" 2>"$RESULTS/loupe.stderr" || rc=$?
    log "loupe check exit code on the corpus: $rc (1 expected: the corpus has $n_bad invalid files)"
    python3 - "$RESULTS/loupe.json" "$CORPUS/MANIFEST.tsv" <<'PY' || true
import json, sys
from pathlib import Path

# loupe's --format json is JSON Lines, one object per diagnostic with "file"
# and "severity"; a file is rejected when it has an error-severity one. Clean
# files produce no lines, so only the rejected set can be compared.
# Errors without a span (e.g. naga's entry-point errors) may carry no file;
# they are counted but can't be attributed.
failing, parsed, anonymous = set(), 0, []
for line in Path(sys.argv[1]).read_text().splitlines():
    try:
        d = json.loads(line)
    except json.JSONDecodeError:
        continue
    if not isinstance(d, dict) or "severity" not in d:
        continue
    parsed += 1
    if str(d["severity"]).lower() != "error":
        continue
    if isinstance(d.get("file"), str):
        failing.add(Path(d["file"]).name)
    else:
        anonymous.append(d.get("message", "?"))
rows = [l.split("\t") for l in Path(sys.argv[2]).read_text().splitlines()[1:]]
bad = {r[0] for r in rows if r[1] == "bad"}
if not parsed:
    print("==> note: no diagnostics found in loupe's JSON output; verdict cross-check skipped", file=sys.stderr)
elif failing == bad and not anonymous:
    print(f"==> loupe and naga reject the same {len(bad)} of {len(rows)} files", file=sys.stderr)
else:
    print(f"==> WARNING: loupe attributes errors to {len(failing)} files, naga rejects {len(bad)}", file=sys.stderr)
    print(f"    only naga rejects: {sorted(bad - failing)}", file=sys.stderr)
    print(f"    only loupe rejects: {sorted(failing - bad)}", file=sys.stderr)
    for m in anonymous:
        print(f"    loupe error with no file: {m}", file=sys.stderr)
PY
fi

# --- timing -----------------------------------------------------------------
# Commands run through `sh -c` (hyperfine's default shell, and the fallback
# below), which expands the globs. All output is discarded: we time checking,
# not terminal rendering.
names=()
cmds=()
if [[ $NAGA_ONLY == 0 ]]; then
    names+=("loupe check --no-device --format json (1 process)")
    cmds+=("$LOUPE check --no-device --format json $CORPUS >/dev/null 2>&1")
fi
names+=("naga FILE, one process per file (${#files[@]} processes)")
cmds+=("for f in $CORPUS/*.wgsl; do $NAGA \"\$f\" >/dev/null 2>&1; done")
names+=("naga --bulk-validate (1 process)")
cmds+=("$NAGA --bulk-validate $CORPUS/*.wgsl >/dev/null 2>&1")

use_hyperfine() { [[ -z ${NO_HYPERFINE:-} ]] && command -v hyperfine >/dev/null; }
if [[ -z ${NO_HYPERFINE:-} ]] && ! command -v hyperfine >/dev/null && command -v apt-get >/dev/null && [[ $(id -u) == 0 ]]; then
    log "installing hyperfine (apt-get)"
    { apt-get install -y hyperfine || { apt-get update && apt-get install -y hyperfine; }; } >/dev/null 2>&1 || true
fi

medians=()
if use_hyperfine; then
    method="hyperfine $(hyperfine --version | cut -d' ' -f2), $WARMUP warm-up + $RUNS runs, median"
    # -i: every command exits non-zero on this corpus by design.
    hyperfine -i --style basic --warmup "$WARMUP" --runs "$RUNS" \
        --export-json "$RESULTS/hyperfine.json" "${cmds[@]}" >&2
    mapfile -t medians < <(python3 -c '
import json, sys
for r in json.load(open(sys.argv[1]))["results"]:
    print("%.6f" % r["median"])' "$RESULTS/hyperfine.json")
else
    # Fallback without hyperfine: $RUNS timed runs per command after warm-up,
    # median of wall times from date +%s%N (nanoseconds).
    method="bash loop with date +%s%N, $WARMUP warm-up + $RUNS runs, median"
    for cmd in "${cmds[@]}"; do
        for ((i = 0; i < WARMUP; i++)); do sh -c "$cmd" || true; done
        samples=()
        for ((i = 0; i < RUNS; i++)); do
            t0=$(date +%s%N)
            sh -c "$cmd" || true
            t1=$(date +%s%N)
            samples+=("$(( t1 - t0 ))")
        done
        medians+=("$(printf '%s\n' "${samples[@]}" | sort -n | python3 -c '
import statistics, sys
print(f"{statistics.median(int(l) for l in sys.stdin) / 1e9:.6f}")')")
        log "$(printf '%-60s median %ss' "$cmd" "${medians[-1]}")"
    done
fi

# --- report -----------------------------------------------------------------
cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -1)
[[ -n $cpu ]] || cpu=$(sed -n 's/^model name\s*: //p' /proc/cpuinfo | head -1)
loupe_version=""
[[ $NAGA_ONLY == 0 ]] && loupe_version=$("$LOUPE" --version 2>/dev/null || true)

# Header facts go through the environment, not into the program text, so a
# CPU name with quotes can't break it.
export BENCH_CORPUS="${#files[@]} WGSL files ($n_bad invalid), $n_lines lines, $((n_bytes / 1024)) KiB, ${CORPUS_ORIGIN:-generated by bench/corpus/gen.py}"
export BENCH_MACHINE="$(nproc) CPUs (nproc), ${cpu:-unknown CPU}"
export BENCH_TOOLS="naga-cli $("$NAGA" --version)${loupe_version:+, $loupe_version}; timing: $method"
python3 - "$NAGA_ONLY" "${#names[@]}" "${names[@]}" "${medians[@]}" <<'PY'
import os, sys
naga_only = sys.argv[1] == "1"
n = int(sys.argv[2])
names, med = sys.argv[3:3 + n], [float(x) for x in sys.argv[3 + n:3 + 2 * n]]
print()
print(f"Corpus: {os.environ['BENCH_CORPUS']}")
print(f"Machine: {os.environ['BENCH_MACHINE']}")
print(f"Tools: {os.environ['BENCH_TOOLS']}")
print("No GPU is involved: with --no-device loupe never creates a wgpu instance or")
print("adapter, so the machine's GPU/adapter does not affect these numbers.")
print()
if naga_only:
    print("| command | median |")
    print("|---|---:|")
    for name, m in zip(names, med):
        print(f"| {name} | {m * 1000:.1f} ms |")
else:
    base = med[0]
    print("| command | median | vs loupe |")
    print("|---|---:|---:|")
    for i, (name, m) in enumerate(zip(names, med)):
        ratio = "1.00x" if i == 0 else f"{m / base:.2f}x"
        print(f"| {name} | {m * 1000:.1f} ms | {ratio} |")
    print()
    print(f"naga per-file / loupe = {med[1] / base:.2f}x; "
          f"naga bulk / loupe = {med[2] / base:.2f}x (above 1: loupe is faster)")
PY
