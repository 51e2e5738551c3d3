#!/bin/sh
# Fuzzes targets in turn, one process on one core, in fork mode so that a
# crash, timeout or OOM is saved under artifacts/<target>/ and fuzzing goes
# on: ./run_all.sh target[:seconds] ... (default: every target, 600 s each).
# Logs go to ../target/fuzz-logs/<target>.log.
set -u
cd "$(dirname "$0")"
LOGS=../target/fuzz-logs
mkdir -p "$LOGS"
for spec in ${@:-obj ply stl npy png scene links align_map landmark}; do
    t=${spec%%:*}
    secs=600
    [ "$t" != "$spec" ] && secs=${spec#*:}
    case $t in
        scene | links | align_map) len=8192 ;;
        landmark) len=256 ;;
        *) len=65536 ;;
    esac
    RUSTC_BOOTSTRAP=1 cargo fuzz run -s none -a "$t" -- \
        -fork=1 -ignore_crashes=1 -ignore_ooms=1 -ignore_timeouts=1 \
        -max_total_time="$secs" -rss_limit_mb=2048 -timeout=10 -max_len="$len" \
        > "$LOGS/$t.log" 2>&1
    echo "$t ${secs}s exit $? $(date -u +%H:%M:%S)" >> "$LOGS/summary.txt"
done
