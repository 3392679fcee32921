#!/usr/bin/env bash
# The fuzz campaign of record: every target of fuzz/harness.rs, 23.4 million executions in all
# (about 4 minutes on two cores), each line of the report as the harness prints it. Exits 1 if any
# input crashed (kept in target/fuzz/crashes/) or was refused with more than one line.
#
#   fuzz/campaign.sh [SEED]
set -euo pipefail
cd "$(dirname "$0")/.."
seed=${1:-1}
cargo build --release --example fuzz
run() { ./target/release/examples/fuzz --seed "$seed" --threads 1 --target "$1" --execs "$2"; }
# Two workers (subshells, each failing if any of its targets fails), the slow SRTM targets spread
# over both.
(
  s=0
  run geotiff 10000000 || s=1
  run hgt 100000 || s=1
  run world-file 1000000 || s=1
  run jobs 1000000 || s=1
  exit $s
) &
first=$!
status=0
(
  s=0
  run png 3000000 || s=1
  run esri-ascii 2000000 || s=1
  run xyz 2000000 || s=1
  run vrt 2000000 || s=1
  run scene 2000000 || s=1
  run hgt-zip 300000 || s=1
  exit $s
) || status=1
wait $first || status=1
exit $status
