#!/usr/bin/env bash
# Instructions per IMU sample of `Preintegrator::integrate_slice` (inclusive), for every scheme
# and level, counted by valgrind's callgrind on 10⁵ samples of the synthetic 200 Hz stream
# (preint/benches/instructions.rs). Counts do not depend on the machine's load.
#
#   tools/instructions.sh                 # all nine figures
#   tools/instructions.sh midpoint        # one scheme
#   PUSH=1 tools/instructions.sh          # one sample at a time through `integrate`
#   BODY=1 tools/instructions.sh          # the IMU away from the body origin (body_p_sensor)
#   BODY=centripetal tools/instructions.sh  # … its lever arm removed per sample (GTSAM's model)
#   INTR=1 tools/instructions.sh          # IMU intrinsics applied to every sample
#   INTR=jacobians tools/instructions.sh  # … and the Jacobians with respect to them
#   FINISH=1 tools/instructions.sh        # instructions of one `finish` (the measurement read
#                                         # out), not per sample
set -euo pipefail
cd "$(dirname "$0")/.."
command -v valgrind >/dev/null || { echo "needs valgrind (apt-get install valgrind)" >&2; exit 2; }
cargo bench -p preint --bench instructions --no-run 2>/dev/null
bin=$(ls -t target/release/deps/instructions-* | grep -v '\.d$' | head -n 1)
n=100000
schemes=${1:-euler midpoint hermite4}
mode=slice
toggle='*Preintegrator*integrate_slice*'
if [ "${PUSH:-0}" = 1 ]; then
  mode=push
  toggle='*push_all*'
fi
label=$mode
per=$n
if [ "${FINISH:-0}" = 1 ]; then
  toggle='*Preintegrator*finish*'
  label="$label, one finish"
  per=1
fi
[ "${BODY:-0}" != 0 ] && label="$label, body_p_sensor ${BODY}"
[ "${INTR:-0}" != 0 ] && label="$label, intrinsics ${INTR}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-9s %10s %12s %10s   (%s)\n' scheme deltas covariance combined "$label"
for s in $schemes; do
  row=()
  for level in deltas covariance combined; do
    valgrind --tool=callgrind --callgrind-out-file="$tmp/out" \
      --toggle-collect="$toggle" "$bin" "$s" "$level" "$n" "$mode" \
      >/dev/null 2>"$tmp/log"
    ir=$(grep -E '^summary:|^totals:' "$tmp/out" | tail -n 1 | awk '{print $2}')
    row+=("$((ir / per))")
  done
  printf '%-9s %10s %12s %10s\n' "$s" "${row[0]}" "${row[1]}" "${row[2]}"
done
