#!/usr/bin/env bash
# Build the fuzz target `model` (docs/reliability.md, "Fuzzing") on the stable toolchain and run
# it for a fixed time: `fuzz/run.sh [SECONDS] [libFuzzer flags...]` (default 60 s). Exits non-zero
# on any finding (a panic, a failed check of the target, a timeout, too much memory), with the
# reproducing input written to fuzz/artifacts/model/. The corpus, fuzz/corpus/model/, is seeded
# with every examples/*.yaml at each run and keeps what the fuzzer adds (neither is committed).
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-60}
shift || true

# cargo-fuzz builds with `-Cpasses=sancov-module` and LLVM options, all stable; only its
# sanitizers need nightly, hence `--sanitizer none`. The version is pinned so that CI builds the
# same flags every run.
version=0.13.2
if ! cargo fuzz --version 2>/dev/null | grep -qx "cargo-fuzz $version"; then
    cargo install cargo-fuzz --locked --version "$version"
fi
cargo fuzz build --sanitizer none model

mkdir -p corpus/model artifacts/model
cp ../examples/*.yaml corpus/model/
host=$(rustc -vV | sed -n 's/^host: //p')
log=artifacts/model/fuzz.log
# -timeout=5: an input that runs longer counts as a hang. Every example runs in at most 30 ms
# through the target; the slowest legitimate input is 4 analyses (the target's cap) each spending
# the kinematic sub-step bound on a driver's pole, about 0.4 s apiece. -max_len=8192: libFuzzer would otherwise grow inputs to the
# largest seed, the 22 KB N-four-bar, whose size only slows parsing and mutation; every other
# example fits. -rss_limit_mb=2048: libFuzzer's default, written out; an execution takes ~45 MB.
status=0
# cargo puts the target under CARGO_TARGET_DIR when that is set, else under fuzz/target.
"${CARGO_TARGET_DIR:-target}/$host/release/model" corpus/model -dict=linkwork.dict -max_total_time="$seconds" -timeout=5 \
    -max_len=8192 -rss_limit_mb=2048 -artifact_prefix=artifacts/model/ -print_final_stats=1 "$@" \
    >"$log" 2>&1 || status=$?
grep -E '^#[0-9]+[[:space:]]+(INITED|DONE)|^stat::' "$log" || true
if [ "$status" -ne 0 ]; then
    echo "fuzz: failed (libFuzzer exit $status); the end of $log:" >&2
    tail -n 40 "$log" | cut -c1-400 >&2
    exit 1
fi
