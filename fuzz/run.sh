#!/usr/bin/env bash
# Long fuzzing run of one target, seeded from the committed seeds plus the
# first 64 KiB of every real log in ../shared/data (copied at run time into
# the git-ignored fuzz/corpus/<target>; never committed).
#   fuzz/run.sh TARGET [SECONDS]        (default 600)
# One process (no -jobs/-workers: with -jobs=1 libFuzzer forks a child that
# logs to fuzz-0.log instead of the terminal), niced for shared machines.
# Extra libFuzzer flags: FUZZ_FLAGS="-dict=..." fuzz/run.sh ulog
set -euo pipefail
cd "$(dirname "$0")/.."
t="${1:?usage: fuzz/run.sh csv|ulog|dataflash|push|audit [seconds]}"
secs="${2:-600}"
export RUSTC_BOOTSTRAP=1
data=../shared/data
corpus="fuzz/corpus/$t"
mkdir -p "$corpus"
prefix() { # file -> corpus/<name>.head (first 64 KiB)
    [ -f "$1" ] && head -c 65536 "$1" >"$corpus/real-$(basename "$1").head" || true
}
case "$t" in
    csv) seeds=(fuzz/seeds/csv); for f in "$data"/csv/*; do prefix "$f"; done ;;
    ulog) seeds=(fuzz/seeds/ulog); for f in "$data"/px4/*.ulg; do prefix "$f"; done ;;
    dataflash) seeds=(fuzz/seeds/dataflash); for f in "$data"/ardupilot/*; do prefix "$f"; done ;;
    audit)
        seeds=(fuzz/seeds/csv fuzz/seeds/ulog fuzz/seeds/dataflash)
        for f in "$data"/csv/* "$data"/px4/*.ulg "$data"/ardupilot/*; do prefix "$f"; done ;;
    push) seeds=(fuzz/seeds/push) ;;
    *) echo "unknown target $t" >&2; exit 2 ;;
esac
dict=()
[ -f "fuzz/dict/$t.dict" ] && dict=(-dict="fuzz/dict/$t.dict")
exec nice -n 19 cargo fuzz run "$t" "$corpus" "${seeds[@]}" -- \
    -max_total_time="$secs" -max_len=65536 -timeout=10 -rss_limit_mb=2048 \
    -print_final_stats=1 "${dict[@]}" ${FUZZ_FLAGS:-}
