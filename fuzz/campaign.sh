#!/usr/bin/env bash
# The fuzz campaign of record: every target of fuzz/harness.rs, 10.6 million executions in all
# (about 5 minutes on two cores), each line of the report as the harness prints it. Exits 1 if any
# input crashed (kept in target/fuzz/crashes/) or was refused with more than one line.
#
#   fuzz/campaign.sh [SEED]
set -euo pipefail
cd "$(dirname "$0")/.."
seed=${1:-1}
cargo build --release --example fuzz
run() { ./target/release/examples/fuzz --seed "$seed" --threads 1 --target "$1" --execs "$2"; }
status=0
# Two workers, the slow SRTM targets spread over both.
{
  run geotiff 4000000 || status=1
  run hgt 100000 || status=1
  run world-file 500000 || status=1
  run jobs 500000 || status=1
} &
first=$!
{
  run png 1000000 || status=1
  run esri-ascii 1000000 || status=1
  run xyz 1000000 || status=1
  run vrt 1000000 || status=1
  run scene 1000000 || status=1
  run hgt-zip 200000 || status=1
  exit $status
} || status=1
wait $first || status=1
exit $status
