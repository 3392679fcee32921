#!/bin/sh
# What each picture feature costs: the terrain pass of jacksboro at 512², in a build from before
# the picture features (commit 3418a4d) and in this one, feature by feature, each line adding to
# the one above (docs/evaluation.md, What each feature costs).
#   OUT=/tmp NOW=target/release/terrain BEFORE=<a build of 3418a4d> REPEAT=30 sh scripts/feature-costs.sh
j() { grep -o "\"$1\":[^,}]*" | head -1 | cut -d: -f2; }
run() {
  label=$1; bin=$2; shift 2
  out=$($bin render sketches/jacksboro.toml -o $OUT/x.png --size 512 --repeat ${REPEAT:-30} --json "$@" 2>&1)
  echo "$label | samples $(echo "$out" | j samples) | gpu_ms $(echo "$out" | j gpu_ms) | terrain $(echo "$out" | grep -o '"terrain":[0-9.]*' | cut -d: -f2) | reference $(echo "$out" | grep -o '"reference":[0-9.]*' | cut -d: -f2)"
}
B=${BEFORE:?a build of commit 3418a4d}; N=${NOW:-target/release/terrain}; OUT=${OUT:-/tmp}
command -v nvidia-smi >/dev/null && nvidia-smi -L | head -1
for mode in warped geomipmap; do
  run "$mode before" $B --mode $mode
  run "$mode shadows=false msaa=off" $N --mode $mode --set render.shadows=false --set render.msaa=off --set render.deferred=false
  run "$mode msaa=off (sketch shadow)" $N --mode $mode --set render.msaa=off --set render.deferred=false
  run "$mode msaa=off deferred (the default on llvmpipe)" $N --mode $mode --set render.msaa=off
  run "$mode msaa=off detail_shadows=true" $N --mode $mode --set render.msaa=off --set render.deferred=false --set render.detail_shadows=true
  run "$mode msaa=4x detail_shadows=true" $N --mode $mode --set render.msaa=4x --set render.detail_shadows=true
  run "$mode msaa=4x (detail off)" $N --mode $mode --set render.msaa=4x
done
run "reference before" $B --mode reference
run "reference msaa=off" $N --mode reference --set render.msaa=off
run "reference msaa=4x" $N --mode reference --set render.msaa=4x
