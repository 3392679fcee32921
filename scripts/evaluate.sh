#!/usr/bin/env bash
# shellcheck disable=SC2016  # the tables' Markdown quotes commands in backticks, on purpose
#
# Regenerates the tables of docs/evaluation.md, each as a Markdown table in that document's
# columns, from the project's own commands.
#
#   scripts/evaluate.sh [--list] [--out DIR] [--bin PATH] [TABLE…]
#
# No TABLE: every table, in the order --list gives. --list: each table's name, its expected
# duration on a 2-core VM with llvmpipe, and what it measures. --out: where runs write their
# outputs and generated data (default target/evaluate). --bin: the terrain binary (default
# target/release/terrain, built by `cargo build --release` when missing). BEFORE=PATH names an
# older build for the tables that compare against one (feature-costs, picture-figures).
#
# Each table starts with a line naming the adapter it ran on, the date and the commit, and each
# run ends with how long every table took. Image figures are deterministic on one adapter; times
# are not, so compare a time only with one measured in the same run.
set -euo pipefail

cd "$(dirname "$0")/.."

OUT=target/evaluate
BIN=target/release/terrain
LIST=0
WANTED=()

# name | expected duration on a 2-core VM (llvmpipe) | what it measures
CATALOGUE='density-ratio|10 s|terrain warp on the six views, guarded and plain: visible cells, demand met, ratio shares, folds
ratio-band|5 s|the density ratio'"'"'s histogram: the share within √2 of the demand, the median, r in [1, 2]
heading-sweep|15 s|demand met and the share in [½, 1] for the hills view turned 0–45°, with and without the turned region
warp-across|4 min|the hills looking east: demand met, ratio shares, GeoMipMap rows matched, triangles warped needs
hills-turn|4 min|the hills view with its region turned 45° and axis-aligned: demand met, rows matched, path PSNR
compare-summary|16 min|terrain compare on four views: frame time to 30 dB and to 1 px, the errors at equal frame time
row-by-row|25 min|warped against GeoMipMap row by row on the six views: rows matched, path PSNR, time ratios, triangles needed
swimming|25 min|LOD change per frame and PSNR along each bundled path, warped held and warped anew, and GeoMipMap
triangulation|15 min|the warped path figures with the fixed split and the adaptive one, and rows matched on triangles
bump-fade|6 min|PSNR and FLIP at warped meshes 96 and 264 and GeoMipMap τ 4 with the bump drawn whole and faded
bump-fade-paths|50 min|rows matched on frame time, path PSNR and LOD change on the six views, bump whole and faded
coarse-fade|6 min|PSNR at warped meshes 16/48/96/144 and GeoMipMap τ 4 b17 / τ 8 b33 with the coarse ground faded (the default)
reference-convergence|6 min|the reference against itself at half its ray-march step, and the meshes against the reference, 128²
cpu-stage|6 min|cargo bench --bench cpu_stage: the stage and its parts on eight views (criterion medians)
error-term-cost|10 s|the geometric-error term'"'"'s cost in the importance (terrain warp --repeat 200)
cpu-stage-flight|8 min|the CPU stage along the bundled flight (300 frames at 128²), held and warped every frame
flight-flicker|5 min|mean absolute difference between consecutive frames of the bundled flight, adaptive and fixed split
tiles-read|2 min|cargo bench --bench tiles: reading one tile, a point query on a decoded tile
lod-timings|3 min|every mode'"'"'s CPU time, GPU time and triangles on jacksboro at 512² (examples/lod_timings)
passes|3 min|jacksboro at 512²: GPU time per pass with the bump, without it, without octaves
counters|5 min|the GPU'"'"'s work per bundled view at 512², warped and GeoMipMap: triangles, pixels of ground, fragments per pixel of ground (pipeline statistics: lavapipe), work per pixel (the counting variant), PSNR against the reference
deferred|6 min|the terrain pass drawn forward and deferred on three views (three runs alternately)
feature-costs|10 min|the terrain pass of jacksboro at 512² feature by feature (scripts/feature-costs.sh)
picture-figures|8 min|contrast, PSNR and SNR of the mesh modes against the reference on the six views
msaa-edges|8 min|the jagged-edge error: PSNR against the reference supersampled 4×, multisampling off and 4×
planet-views|3 min|the planet views: triangles, PSNR against the reference at 256², frame time at 512²
planet-sweep|25 min|terrain compare on the three planet views: clipmaps'"'"' φ steps × rings per level
planet-tangent-warp|5 min|the warped mode on a tangent-plane map of the planet, beside clipmaps
planet-flight|4 min|the planet flight from 20,000 km to 2 m: 120 frames at 512², median and p95 frame time
fold-census|3 min|the fold guard'"'"'s rounds against the shared warp over random cameras (examples/fold_census)
tiles-convert|4 min|a 32,768² mosaic converted to a tile pyramid: time, peak memory, size, tiles
stream-flight|30 min|200 frames flown over the 32k pyramid in four ways: memory, frame time, tiles, stand-ins
relief|1 min|the relief measure straight down (sun 315° at 45°, shadows off) on every bundled sketch and the surface fixtures
pictures|3 min|the gallery: every bundled view, two user DEMs natural, with colour ramps and with imagery, into docs/pictures/gallery/'

usage() {
  sed -n '4,14p' "$0" | sed 's/^# \{0,1\}//'
}

while [ $# -gt 0 ]; do
  case $1 in
    --list) LIST=1 ;;
    --out) OUT=${2:?--out needs a folder}; shift ;;
    --bin) BIN=${2:?--bin needs a path}; shift ;;
    -h | --help) usage; exit 0 ;;
    -*) echo "evaluate.sh: unknown option $1" >&2; usage >&2; exit 2 ;;
    *) WANTED+=("$1") ;;
  esac
  shift
done

names() { printf '%s\n' "$CATALOGUE" | cut -d'|' -f1; }

if [ "$LIST" = 1 ]; then
  printf '%s\n' "$CATALOGUE" | awk -F'|' '{ printf "%-22s %-8s %s\n", $1, $2, $3 }'
  exit 0
fi

for t in "${WANTED[@]+"${WANTED[@]}"}"; do
  if ! names | grep -qx -- "$t"; then
    echo "evaluate.sh: no table named $t (scripts/evaluate.sh --list names them)" >&2
    exit 2
  fi
done
if [ ${#WANTED[@]} -eq 0 ]; then
  mapfile -t WANTED < <(names)
fi

if [ ! -x "$BIN" ]; then
  if [ "$BIN" = target/release/terrain ]; then
    cargo build --release >&2
  else
    echo "evaluate.sh: $BIN is not an executable" >&2
    exit 2
  fi
fi
mkdir -p "$OUT"
LOG=$OUT/evaluate.log
: >"$LOG"

VIEWS=(jacksboro jacksboro-high gaussian gaussian-high hills hills-high)
PLANETS=(orbit 10km ground)

# ---------------------------------------------------------------------------------------------
# Helpers

terrain() { TERRAIN_QUIET=1 "$BIN" "$@" 2>>"$LOG"; }

ADAPTER=
adapter() {
  if [ -z "$ADAPTER" ]; then
    ADAPTER=$(terrain render sketches/jacksboro.toml -o "$OUT/adapter.png" --size 16 --json |
      jq -r '.adapter')
  fi
  printf '%s' "$ADAPTER"
}

# The line above every table: what ran it, when, from which commit, and the command. A second
# argument, cpu, names the processor instead of the adapter, for tables that render nothing.
head_line() {
  local commit machine
  if [ "${2:-}" = cpu ]; then
    machine="$(nproc) cores, $(awk -F': ' '/model name/ { print $2; exit }' /proc/cpuinfo 2>/dev/null || echo 'CPU')"
  else
    machine=$(adapter)
  fi
  commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
  if ! git diff --quiet HEAD 2>/dev/null; then commit="$commit+changes"; fi
  printf '\n*%s: %s, %s, commit %s; `scripts/evaluate.sh %s`*\n\n' \
    "$1" "$machine" "$(date -u +%F)" "$commit" "$1"
}

# `terrain compare` into $OUT/compare/KEY, once per run of this script for the same KEY.
declare -A COMPARED=()
compare() {
  local key=$1 scene=$2
  shift 2
  local dir=$OUT/compare/$key
  if [ -z "${COMPARED[$key]:-}" ]; then
    rm -rf "$dir"
    terrain compare "$scene" --out-dir "$dir" "$@" >/dev/null
    COMPARED[$key]=1
  fi
  printf '%s' "$dir"
}

# jq's numbers print without trailing zeros; fx(d) writes d decimals, as the tables do.
FX='def fx(d): (. * pow(10; d) | round) as $n | ($n | fabs | tostring) as $s
  | (if ($s | length) <= d then ("0" * (d + 1 - ($s | length))) + $s else $s end) as $p
  | (if $n < 0 then "-" else "" end) + $p[0:($p | length) - d] + (if d > 0 then "." + $p[($p | length) - d:] else "" end);'
jq() { # jq with fx defined: the first argument that is neither an option nor an option's value is the filter
  local args=() filtered=0
  while [ $# -gt 0 ]; do
    case $1 in
      --arg | --argjson) args+=("$1" "$2" "$3"); shift 3 ;;
      -*) args+=("$1"); shift ;;
      *)
        if [ $filtered = 0 ]; then args+=("$FX $1"); filtered=1; else args+=("$1"); fi
        shift ;;
    esac
  done
  command jq "${args[@]}"
}

# A compare row's field: DIR MODE SETTING FIELD, "—" when the sweep has no such row.
row() {
  jq -r --arg m "$2" --arg s "$3" --arg f "$4" \
    '[.rows[] | select(.mode == $m and .setting == $s) | .[$f]] | if length == 0 then "—" else .[0] end' \
    "$1/report.json"
}

# Rounds a number to D decimals ("—" passes through).
fix() { awk -v d="$1" -v x="${2:-}" 'BEGIN { if (x == "—" || x == "null" || x == "") print "—"; else printf "%.*f\n", d, x }'; }

# The path's mean of FIELD for MODE (its setting at the scene's own quality).
path_mean() {
  jq -r --arg m "$2" --arg f "$3" \
    '[(.path.modes // [])[] | select(.mode == $m) | .[$f].mean] | if length == 0 then "—" else .[0] end' \
    "$1/report.json"
}

dominance() { jq -r ".summary.dominance.$2 // \"—\"" "$1/report.json"; }

# warped's fastest row with at least each GeoMipMap row's PSNR, as a multiple of its time: the
# range over GeoMipMap's rows.
time_ratio_range() {
  jq -r '[.rows[] | select(.mode == "warped")] as $w
    | [.rows[] | select(.mode == "geomipmap") | . as $g
       | [$w[] | select(.psnr_db >= $g.psnr_db) | .frame_ms] | min as $t
       | if $t == null then empty else $t / $g.frame_ms end]
    | if length == 0 then "—" else "\(min | fx(2))–\(max | fx(2))×" end' \
    "$1/report.json"
}

median() { sort -g | awk '{ a[NR] = $1 } END { if (NR == 0) print "—"; else print (NR % 2 ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2) }'; }

# The median and 95th percentile (nearest rank) of a frames.csv column.
csv_stats() {
  python3 - "$1" "$2" <<'EOF'
import csv, math, sys
with open(sys.argv[1]) as f:
    v = sorted(float(r[sys.argv[2]]) for r in csv.DictReader(f) if r[sys.argv[2]])
n = len(v)
med = v[n // 2] if n % 2 else (v[n // 2 - 1] + v[n // 2]) / 2
print(f"{med:.1f} {v[max(0, math.ceil(0.95 * n) - 1)]:.1f}")
EOF
}

# Criterion's median estimate of GROUP/BENCH in µs (or ns with a third argument).
criterion_median() {
  local f=target/criterion/$1/$2/new/estimates.json
  if [ ! -f "$f" ]; then echo "—"; return; fi
  jq -r --arg ns "${3:-}" '.median.point_estimate | if $ns == "" then . / 1000 | fx(1) else round end' "$f"
}

hills_at() { # heading in degrees → --set arguments placing the hills camera 2.5 km from the centre
  awk -v a="$1" 'BEGIN { r = a * atan2(0, -1) / 180; s = sin(r); c = cos(r);
    printf "--set camera.position=[%.1f,%.1f,760.0] --set camera.look_at=[%.1f,%.1f,400.0]\n",
      3840 - 2500 * s, 3840 - 2500 * c, 3840 + 2500 * s, 3840 + 2500 * c }'
}
HILLS_EAST=(--set 'camera.position=[500.0,3500.0,760.0]' --set 'camera.look_at=[7933.0,3500.0,400.0]')

# ---------------------------------------------------------------------------------------------
# The tables, one function each (table-NAME).

table-density-ratio() {
  head_line density-ratio cpu
  echo '| scene | method | visible cells | their demand met | ratio in [½, 2] | in [½, 1] | flipped | guarded columns |'
  echo '|---|---|---|---|---|---|---|---|'
  local v m
  for v in "${VIEWS[@]}"; do
    for m in guarded plain; do
      terrain warp "sketches/$v.toml" --out-dir "$OUT/warp/$v-$m" --method "$m" --no-figures --json |
        jq -r --arg v "$v" --arg m "$m" '"| \($v) | \($m) | \(.cells_visible) | \(.demand_met | fx(3)) | \(.ratio_within_0_5_2 * 100 | fx(1)) % | \(.ratio_within_0_5_1 * 100 | fx(1)) % | \(.flipped_cells) | \(if $m == "plain" then "—" else .guarded_columns end) |"'
    done
  done
}

table-ratio-band() {
  head_line ratio-band cpu
  echo '| view | within √2 of the demand | cells in [0.71, 1) | in [1, 1.41) | median ratio | r in [1, 2] (demanded over obtained in [½, 1]) |'
  echo '|---|---|---|---|---|---|'
  local v
  for v in "${VIEWS[@]}"; do
    terrain warp "sketches/$v.toml" --out-dir "$OUT/warp/$v-band" --no-figures --json |
      jq -r --arg v "$v" '
        def bin(lo): [.histogram[] | select((.lo - lo) | fabs < 1e-6) | .cells][0];
        (bin(0.7071067811865476)) as $a | (bin(1)) as $b | (bin(1.4142135623730951)) as $c
        | "| \($v) | \(($a + $b) / .cells_visible * 100 | fx(1)) % | \($a) | \($b) | \(.ratio_median | fx(2)) | \(($b + $c) / .cells_visible * 100 | fx(1)) % |"'
  done
}

table-heading-sweep() {
  head_line heading-sweep cpu
  local a d line1="| demand met, axes along x and y |" line2="| demand met, turned past 30° |" line3="| within [½, 1], axes / turned |"
  local -a set
  for a in 0 10 20 30 35 40 45; do
    read -ra set <<<"$(hills_at "$a")"
    local r=()
    for d in false true; do
      r+=("$(terrain warp sketches/hills.toml --out-dir "$OUT/warp/heading-$a-$d" --no-figures --json \
        "${set[@]}" --set "warp.diagonal=$d" | jq -r '"\(.demand_met | fx(3)) \(.ratio_within_0_5_1 * 100 | fx(1))"')")
    done
    read -r dm0 s0 <<<"${r[0]}"
    read -r dm1 s1 <<<"${r[1]}"
    line1="$line1 $(fix 3 "$dm0") |"
    line2="$line2 $(fix 3 "$dm1") |"
    line3="$line3 $s0 / $s1 % |"
  done
  echo '| heading from north | 0° | 10° | 20° | 30° | 35° | 40° | 45° |'
  echo '|---|---|---|---|---|---|---|---|'
  printf '%s\n%s\n%s\n' "$line1" "$line2" "$line3"
}

table-warp-across() {
  head_line warp-across
  echo '| hills looking east | demand met | ratio in [½, 2] | in [½, 1] | GeoMipMap rows matched on triangles and error | triangles warped needs, interpolated |'
  echo '|---|---|---|---|---|---|'
  local w dir
  w=$(terrain warp sketches/hills.toml --out-dir "$OUT/warp/hills-east" --no-figures --json "${HILLS_EAST[@]}" |
    jq -r '"\(.demand_met | fx(3)) | \(.ratio_within_0_5_2 * 100 | fx(1)) % | \(.ratio_within_0_5_1 * 100 | fx(1)) % | across: \(.across)"')
  dir=$(compare hills-east sketches/hills.toml --modes warped,geomipmap --repeat 1 --path-frames 0 "${HILLS_EAST[@]}")
  echo "| across | ${w%% | across*} | $(dominance "$dir" matched_on_triangles) of $(dominance "$dir" geomipmap_rows) | $(fix 3 "$(dominance "$dir" need.geometric_mean)")× |"
}

table-hills-turn() {
  head_line hills-turn
  echo '| hills, looking north-east | demand met | ratio in [½, 2] | in [½, 1] | GeoMipMap rows matched on triangles and error / on frame time and PSNR | triangles warped needs, interpolated | PSNR along the path |'
  echo '|---|---|---|---|---|---|---|'
  local d label dir w
  for d in false true; do
    if [ $d = false ]; then label='axes along x and y (`--set warp.diagonal=false`)'; else label='turned 45°'; fi
    w=$(terrain warp sketches/hills.toml --out-dir "$OUT/warp/hills-turn-$d" --no-figures --json --set "warp.diagonal=$d" |
      jq -r '"\(.demand_met | fx(3)) | \(.ratio_within_0_5_2 * 100 | fx(1)) % | \(.ratio_within_0_5_1 * 100 | fx(1)) %"')
    dir=$(compare "hills-turn-$d" sketches/hills.toml --modes warped,geomipmap --repeat 1 --set "warp.diagonal=$d")
    echo "| $label | $w | $(dominance "$dir" matched_on_triangles) / $(dominance "$dir" matched_on_time) of $(dominance "$dir" geomipmap_rows) | $(fix 3 "$(dominance "$dir" need.geometric_mean)")× | $(fix 2 "$(path_mean "$dir" warped psnr_db)") dB |"
  done
}

table-compare-summary() {
  head_line compare-summary
  echo '| view | mode | frame time to 30 dB | frame time to 1 px mean error | at equal frame time |'
  echo '|---|---|---|---|---|'
  local v dir
  for v in jacksboro jacksboro-high gaussian gaussian-high; do
    dir=$(compare "$v-all" "sketches/$v.toml")
    jq -r --arg v "$v" '
      def ms: if . == null then null else (. * 1 | round | tostring) + " ms" end;
      def best($m): [.rows[] | select(.mode == $m) | .psnr_db] | max | fx(1);
      . as $r | .summary.budget_ms as $b
      | .summary.modes | to_entries[]
      | .key as $i | .value as $s
      | "| \(if $i == 0 then $v else "" end) | \($s.display) | \(if $s.ms_to_30db == null then "not reached (best \($r | best($s.mode)) dB)" else "\($s.ms_to_30db | ms) (\($s.setting_30db))" end) | \(if $s.ms_to_1px == null then "not reached" else "\($s.ms_to_1px | ms) (\($s.setting_1px))" end) | \($s.psnr_at_budget_db | fx(1)) dB, \($s.sse_at_budget_px | fx(2)) px\(if $i == 0 then " at \($b | ms)" else "" end) |"' \
      "$dir/report.json"
  done
}

table-row-by-row() {
  head_line row-by-row
  echo '| view | triangles and error | frame time and PSNR | PSNR along the path, warped | warped'"'"'s time for GeoMipMap'"'"'s PSNR | triangles warped needs, interpolated |'
  echo '|---|---|---|---|---|---|'
  local v dir
  for v in "${VIEWS[@]}"; do
    dir=$(compare "$v-wg" "sketches/$v.toml" --modes warped,geomipmap)
    echo "| $v | $(dominance "$dir" matched_on_triangles) | $(dominance "$dir" matched_on_time) | $(fix 2 "$(path_mean "$dir" warped psnr_db)") dB | $(time_ratio_range "$dir") | $(fix 2 "$(dominance "$dir" need.least)")–$(fix 2 "$(dominance "$dir" need.greatest)")×, $(fix 3 "$(dominance "$dir" need.geometric_mean)") |"
  done
}

table-swimming() {
  head_line swimming
  echo '| path | LOD change per frame, warped every frame → held | PSNR along the path, every frame → held | GeoMipMap (`--modes geomipmap`) |'
  echo '|---|---|---|---|'
  local v scene anew held
  for v in jacksboro jacksboro-flight gaussian hills jacksboro-high gaussian-high hills-high; do
    scene=sketches/$v.toml
    anew=$(compare "$v-anew" "$scene" --modes warped --repeat 1 --path-frames 24 --set warp.hold=false)
    held=$(compare "$v-wg-path" "$scene" --modes warped,geomipmap --repeat 1 --path-frames 24)
    echo "| $v | $(fix 3 "$(path_mean "$anew" warped lod_change_levels)") → $(fix 3 "$(path_mean "$held" warped lod_change_levels)") levels | $(fix 2 "$(path_mean "$anew" warped psnr_db)") → $(fix 2 "$(path_mean "$held" warped psnr_db)") dB | $(fix 3 "$(path_mean "$held" geomipmap lod_change_levels)") levels, $(fix 2 "$(path_mean "$held" geomipmap psnr_db)") dB |"
  done
}

table-triangulation() {
  head_line triangulation
  echo '| path | PSNR | mean screen-space error | LOD change per frame | rows matched on triangles and error |'
  echo '|---|---|---|---|---|'
  local v fixed adaptive
  for v in "${VIEWS[@]}"; do
    fixed=$(compare "$v-fixed" "sketches/$v.toml" --modes warped,geomipmap --repeat 1 --set warp.triangulation=fixed)
    adaptive=$(compare "$v-wg-path" "sketches/$v.toml" --modes warped,geomipmap --repeat 1 --path-frames 24)
    echo "| $v | $(fix 2 "$(path_mean "$fixed" warped psnr_db)") → $(fix 2 "$(path_mean "$adaptive" warped psnr_db)") dB | $(fix 3 "$(path_mean "$fixed" warped sse_mean_px)") → $(fix 3 "$(path_mean "$adaptive" warped sse_mean_px)") px | $(fix 3 "$(path_mean "$fixed" warped lod_change_levels)") → $(fix 3 "$(path_mean "$adaptive" warped lod_change_levels)") levels | $(dominance "$fixed" matched_on_triangles) → $(dominance "$adaptive" matched_on_triangles) |"
  done
}

table-bump-fade() {
  head_line bump-fade
  echo '| view | warped, mesh 96 | warped, mesh 264 | GeoMipMap τ 4, blocks of 17 | FLIP, warped mesh 96 |'
  echo '|---|---|---|---|---|'
  local v whole faded
  for v in gaussian jacksboro jacksboro-high gaussian-high; do
    whole=$(compare "$v-whole" "sketches/$v.toml" --modes warped,geomipmap --repeat 1 --path-frames 0 --set detail.bump_fade=false)
    faded=$(compare "$v-faded" "sketches/$v.toml" --modes warped,geomipmap --repeat 1 --path-frames 0)
    local cells=()
    local spec
    for spec in 'warped|quad_px=2 mesh=96 fixed|psnr_db' 'warped|quad_px=2 mesh=264 fixed|psnr_db' 'geomipmap|tau=4 block=17|psnr_db' 'warped|quad_px=2 mesh=96 fixed|flip_mean'; do
      IFS='|' read -r m s f <<<"$spec"
      local d=2
      [ "$f" = flip_mean ] && d=3
      cells+=("$(fix $d "$(row "$whole" "$m" "$s" "$f")") → $(fix $d "$(row "$faded" "$m" "$s" "$f")")")
    done
    echo "| $v | ${cells[0]} dB | ${cells[1]} | ${cells[2]} | ${cells[3]} |"
  done
}

table-bump-fade-paths() {
  head_line bump-fade-paths
  echo '| view | GeoMipMap rows matched on frame time and PSNR | warped PSNR along the path | warped LOD change per frame | GeoMipMap PSNR along the path |'
  echo '|---|---|---|---|---|'
  local v whole faded
  for v in "${VIEWS[@]}"; do
    whole=$(compare "$v-wg-whole" "sketches/$v.toml" --modes warped,geomipmap --set detail.bump_fade=false)
    faded=$(compare "$v-wg" "sketches/$v.toml" --modes warped,geomipmap)
    echo "| $v | $(dominance "$whole" matched_on_time) → $(dominance "$faded" matched_on_time) | $(fix 2 "$(path_mean "$whole" warped psnr_db)") → $(fix 2 "$(path_mean "$faded" warped psnr_db)") dB | $(fix 3 "$(path_mean "$whole" warped lod_change_levels)") → $(fix 3 "$(path_mean "$faded" warped lod_change_levels)") levels | $(fix 2 "$(path_mean "$whole" geomipmap psnr_db)") → $(fix 2 "$(path_mean "$faded" geomipmap psnr_db)") dB |"
  done
}

table-coarse-fade() {
  head_line coarse-fade
  echo '| coarse ground'"'"'s octaves | gaussian | hills |'
  echo '|---|---|---|'
  local v dir cells=()
  for v in gaussian hills; do
    dir=$(compare "$v-faded" "sketches/$v.toml" --modes warped,geomipmap --repeat 1 --path-frames 0)
    local vals=() s
    for s in 16 48 96 144; do vals+=("$(fix 2 "$(row "$dir" warped "quad_px=2 mesh=$s fixed" psnr_db)")"); done
    vals+=("$(fix 2 "$(row "$dir" geomipmap 'tau=4 block=17' psnr_db)")" "$(fix 2 "$(row "$dir" geomipmap 'tau=8 block=33' psnr_db)")")
    local joined
    joined=$(IFS=/; echo "${vals[*]}")
    cells+=("${joined//\// / }")
  done
  echo "| faded, the model's factor (this build) | ${cells[0]} dB | ${cells[1]} |"
}

table-reference-convergence() {
  head_line reference-convergence
  echo '| view | reference at half its step | warped, scene setting | GeoMipMap, τ 1 blocks of 33 |'
  echo '|---|---|---|---|'
  local v dir
  for v in "${VIEWS[@]}"; do
    dir=$(compare "$v-128" "sketches/$v.toml" --size 128 --modes warped,geomipmap --repeat 1 --path-frames 0)
    echo "| $v | $(fix 2 "$(jq -r '.reference.psnr_halving_step_db' "$dir/report.json")") dB | $(fix 2 "$(row "$dir" warped 'quad_px=2 mesh=512' psnr_db)") dB | $(fix 2 "$(row "$dir" geomipmap 'tau=1 block=33' psnr_db)") dB |"
  done
}

table-cpu-stage() {
  head_line cpu-stage cpu
  cargo bench --bench cpu_stage >>"$LOG" 2>&1
  echo '| view | stage | stage, held | sketch map | importance | warp (guarded) | warp (plain) |'
  echo '|---|---|---|---|---|---|---|'
  local g label b cells
  for g in jacksboro jacksboro-high gaussian gaussian-high hills hills-axes hills-high hills-east; do
    case $g in
      jacksboro) label='jacksboro, near' ;;
      jacksboro-high) label='jacksboro, high' ;;
      gaussian) label='gaussian, near' ;;
      gaussian-high) label='gaussian, high' ;;
      hills) label='hills, near (north-east: turned)' ;;
      hills-axes) label='hills, near, axes along x and y' ;;
      hills-high) label='hills, high' ;;
      hills-east) label='hills, near, looking east' ;;
    esac
    cells="| $label |"
    for b in stage stage_held sketch_map importance warp_guarded warp_plain; do
      cells="$cells $(criterion_median "$g" "$b") µs |"
    done
    echo "$cells"
  done
}

table-error-term-cost() {
  head_line error-term-cost cpu
  echo '| jacksboro near | importance | stage |'
  echo '|---|---|---|'
  local e
  for e in true false; do
    terrain warp sketches/jacksboro.toml --out-dir "$OUT/warp/error-$e" --no-figures --json --repeat 200 --set "importance.error=$e" |
      jq -r --arg e "$e" '"| importance.error = \($e) | \(.importance_us | fx(1)) µs | \(.cpu_stage_us | fx(1)) µs |"'
  done
}

fly_flight() { # KEY [--set …]: the bundled flight at 128², 300 frames; prints the folder
  local key=$1 dir=$OUT/fly/$1
  shift
  if [ -z "${COMPARED[fly-$key]:-}" ]; then
    rm -rf "$dir"
    terrain fly sketches/jacksboro-flight.toml --out-dir "$dir" --size 128 --no-mp4 --frames 300 "$@" >/dev/null
    COMPARED[fly-$key]=1
  fi
  printf '%s' "$dir"
}

table-cpu-stage-flight() {
  head_line cpu-stage-flight
  echo '| the bundled flight, 300 frames at 128² | stage median | p95 |'
  echo '|---|---|---|'
  local k label dir m p
  for k in held anew axes; do
    case $k in
      held) label='held (`warp.hold`, the default)'; dir=$(fly_flight held) ;;
      anew) label='every frame warped (`--set warp.hold=false`)'; dir=$(fly_flight anew --set warp.hold=false) ;;
      axes) label='held, axes along x and y (`--set warp.diagonal=false`)'; dir=$(fly_flight axes --set warp.diagonal=false) ;;
    esac
    read -r m p <<<"$(csv_stats "$dir/frames.csv" cpu_stage_us)"
    echo "| $label | $m µs | $p µs |"
  done
}

table-flight-flicker() {
  head_line flight-flicker
  echo '| the bundled flight, 300 frames at 128² | mean | median | 95th percentile |'
  echo '|---|---|---|---|'
  local k label dir
  for k in held fixed whole; do
    case $k in
      held) label='adaptive split, bump faded (the defaults)'; dir=$(fly_flight held) ;;
      fixed) label='fixed split (`--set warp.triangulation=fixed`)'; dir=$(fly_flight fixed --set warp.triangulation=fixed) ;;
      whole) label='bump drawn whole (`--set detail.bump_fade=false`)'; dir=$(fly_flight whole --set detail.bump_fade=false) ;;
    esac
    python3 - "$dir" "$label" <<'EOF'
import glob, sys
import numpy as np
from PIL import Image
frames = sorted(glob.glob(sys.argv[1] + "/frame-*.png"))
d = []
prev = None
for f in frames:
    img = np.asarray(Image.open(f).convert("RGB"), dtype=np.float64)
    if prev is not None:
        d.append(np.abs(img - prev).mean())
    prev = img
d = np.array(d)
print(f"| {sys.argv[2]} | {d.mean():.2f} levels | {np.median(d):.2f} | {np.percentile(d, 95):.2f} |")
EOF
  done
}

table-tiles-read() {
  head_line tiles-read cpu
  cargo bench --bench tiles >>"$LOG" 2>&1
  echo '| benchmark | median |'
  echo '|---|---|'
  local f
  for f in target/criterion/tiles/*/new/estimates.json; do
    [ -f "$f" ] || continue
    jq -r --arg n "$(basename "$(dirname "$(dirname "$f")")")" \
      '"| \($n) | \(.median.point_estimate | if . > 1000 then "\(. / 1000 | round) µs" else "\(round) ns" end) |"' "$f"
  done
}

table-lod-timings() {
  head_line lod-timings
  cargo run --release --example lod_timings 2>>"$LOG" | grep '^|'
}

table-passes() {
  head_line passes
  echo '| detail | GPU | warp_zoom | mesh_split | normals | terrain | CPU stage |'
  echo '|---|---|---|---|---|---|---|'
  local label
  local -a set
  for label in '12 octaves with bump (scene)' '`--set detail.bump=false`' '`--set detail.octaves=0`'; do
    case $label in
      12*) set=() ;;
      *bump*) set=(--set detail.bump=false) ;;
      *) set=(--set detail.octaves=0) ;;
    esac
    terrain render sketches/jacksboro.toml -o "$OUT/passes.png" --repeat 10 --json "${set[@]+"${set[@]}"}" |
      jq -r --arg l "$label" '"| \($l) | \(.gpu_ms | fx(1)) ms | \(.passes_ms.warp_zoom | fx(1)) ms | \(.passes_ms.mesh_split | fx(1)) ms | \(.passes_ms.normals | fx(1)) ms | \(.passes_ms.terrain | fx(1)) ms | \(.cpu_stage_us / 1000 | fx(1)) ms |"'
  done
}

table-counters() {
  head_line counters
  echo '| view | mode | triangles | pixels of ground | fragments per pixel of ground | octaves / shadow steps / atlas taps per pixel of ground | vertex invocations | primitives | PSNR |'
  echo '|---|---|---|---|---|---|---|---|---|'
  local v m psnr
  for v in "${VIEWS[@]}"; do
    terrain render "sketches/$v.toml" -o "$OUT/counters-ref.png" --size 512 --mode reference >/dev/null
    for m in warped geomipmap; do
      terrain render "sketches/$v.toml" -o "$OUT/counters.png" --size 512 --mode "$m" --json >"$OUT/counters.json"
      psnr=$(cargo run --release --example image_metrics -- "$OUT/counters-ref.png" "$OUT/counters.png" 2>>"$LOG" | awk '{ print $2 }')
      jq -r --arg v "$v" --arg m "$m" --arg psnr "$(fix 2 "$psnr")" 'if .counters == null then error("the adapter counts nothing: install mesa-vulkan-drivers (lavapipe)") else . end
          | "| \($v) | \($m) | \(.triangles) | \(.covered_px) | \(.fragments_per_covered_px | fx(2)) | \(.work_per_px.octaves | fx(2)) / \(.work_per_px.shadow_steps | fx(2)) / \(.work_per_px.atlas_taps | fx(1)) | \([.counters[].vertex_invocations] | add) | \([.counters[].primitives] | add) | \($psnr) dB |"' "$OUT/counters.json"
    done
  done
}

table-deferred() {
  head_line deferred
  echo '| | warped | GeoMipMap |'
  echo '|---|---|---|'
  local view cells mode d
  for view in gaussian jacksboro jacksboro-high; do
    cells=()
    for mode in warped geomipmap; do
      local -a args=(render "sketches/$view.toml" -o "$OUT/deferred.png" --json --mode "$mode")
      case $view in
        gaussian) args+=(--size 256 --repeat 15)
          if [ $mode = warped ]; then args+=(--set warp.budget=false --set warp.mesh=61); else args+=(--tau 8 --set geomipmap.block=17); fi ;;
        *) args+=(--size 512 --repeat 10) ;;
      esac
      local fwd=() def=()
      for _ in 1 2 3; do
        for d in false true; do
          local t
          t=$(terrain "${args[@]}" --set "render.deferred=$d" | jq -r '.passes_ms.terrain')
          if [ $d = false ]; then fwd+=("$t"); else def+=("$t"); fi
        done
      done
      cells+=("$(fix 1 "$(printf '%s\n' "${fwd[@]}" | median)") → $(fix 1 "$(printf '%s\n' "${def[@]}" | median)") ms")
    done
    case $view in
      gaussian) echo "| gaussian at 256², warped mesh 61², GeoMipMap τ 8, blocks of 17 | ${cells[0]} | ${cells[1]} |" ;;
      jacksboro) echo "| jacksboro at 512², the scene's settings | ${cells[0]} | ${cells[1]} |" ;;
      *) echo "| jacksboro-high at 512² | ${cells[0]} | ${cells[1]} |" ;;
    esac
  done
}

table-feature-costs() {
  head_line feature-costs
  echo '| feature (each line adding to the one above) | samples | GPU ms | terrain pass ms | reference ms |'
  echo '|---|---|---|---|---|'
  OUT=$OUT NOW=$BIN BEFORE=${BEFORE:-$BIN} REPEAT=${REPEAT:-8} sh scripts/feature-costs.sh 2>>"$LOG" |
    awk -F' [|] ' '/\|/ { gsub(/samples |gpu_ms |terrain |reference /, ""); printf "| %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5 }'
  if [ -z "${BEFORE:-}" ]; then echo; echo '("before" rows ran this build: set BEFORE to a build of 3418a4d for the earlier renderer.)'; fi
}

PICTURES=
picture_figures() {
  if [ -z "$PICTURES" ]; then
    PICTURES=$OUT/picture-figures.md
    local -a before=()
    if [ -n "${BEFORE:-}" ]; then before=(--before "$BEFORE"); fi
    python3 scripts/picture-figures.py --terrain "$BIN" "${before[@]+"${before[@]}"}" >"$PICTURES" 2>>"$LOG"
  fi
  printf '%s' "$PICTURES"
}

table-picture-figures() {
  head_line picture-figures
  awk 'NF == 0 { exit } { print }' "$(picture_figures)"
}

table-msaa-edges() {
  head_line msaa-edges
  awk 'NF == 0 { seen = 1; next } seen { print }' "$(picture_figures)"
}

table-planet-views() {
  head_line planet-views
  echo '| view | triangles (512²) | PSNR 256² | frame, 512² |'
  echo '|---|---|---|---|'
  local p json psnr
  for p in "${PLANETS[@]}"; do
    terrain render "sketches/planet-$p.toml" -o "$OUT/planet-$p-ref.png" --size 256 --mode reference >/dev/null
    terrain render "sketches/planet-$p.toml" -o "$OUT/planet-$p.png" --size 256 >/dev/null
    psnr=$(cargo run --release --example image_metrics -- "$OUT/planet-$p-ref.png" "$OUT/planet-$p.png" 2>>"$LOG" | awk '{ print $2 }')
    json=$(terrain render "sketches/planet-$p.toml" -o "$OUT/planet-$p-512.png" --size 512 --repeat 5 --json)
    echo "| $p | $(jq -r .triangles <<<"$json") | $(fix 2 "$psnr") dB | $(jq -r '.frame_ms | round' <<<"$json") ms |"
  done
}

planet_cell() { # DIR SETTING → "triangles, PSNR"
  printf '%s, %s dB' "$(row "$1" clipmaps "$2" triangles)" "$(fix 2 "$(row "$1" clipmaps "$2" psnr_db)")"
}

table-planet-sweep() {
  head_line planet-sweep
  echo '| φ steps × rings per level | orbit: triangles, PSNR | 10 km: triangles, PSNR, mean error, LOD change | 2 m: triangles, PSNR, mean error, LOD change | 2 m: frame |'
  echo '|---|---|---|---|---|'
  local p
  for p in "${PLANETS[@]}"; do compare "planet-$p" "sketches/planet-$p.toml" >/dev/null; done
  local o=$OUT/compare/planet-orbit k=$OUT/compare/planet-10km g=$OUT/compare/planet-ground
  jq -r '.rows[] | .setting' "$o/report.json" | while read -r s; do
    echo "| $s | $(planet_cell "$o" "$s") | $(planet_cell "$k" "$s"), $(fix 3 "$(row "$k" clipmaps "$s" sse_mean_px)") px, $(fix 2 "$(row "$k" clipmaps "$s" lod_change_levels)") | $(planet_cell "$g" "$s"), $(fix 3 "$(row "$g" clipmaps "$s" sse_mean_px)") px, $(fix 2 "$(row "$g" clipmaps "$s" lod_change_levels)") | $(fix 0 "$(row "$g" clipmaps "$s" frame_ms)") ms |"
  done
}

table-planet-tangent-warp() {
  head_line planet-tangent-warp
  local p
  for p in "${PLANETS[@]}"; do
    cargo run --release --example planet_tangent_warp "sketches/planet-$p.toml" 2>>"$LOG"
    echo
  done
}

table-planet-flight() {
  head_line planet-flight
  echo '| flight | frames | frame time median | p95 | p95 / median | the whole flight |'
  echo '|---|---|---|---|---|---|'
  terrain fly sketches/planet-flight.toml --out-dir "$OUT/fly/planet" --frames 120 --size 512 --no-mp4 --json |
    jq -r '"| 20,000 km → 2 m | \(.frames) | \(.frame_ms_median | fx(1)) ms | \(.frame_ms_p95 | fx(1)) ms | \(.spread_p95_over_median | fx(2)) | \(.elapsed_s | fx(1)) s |"'
}

table-fold-census() {
  head_line fold-census cpu
  cargo run --release --example fold_census 2>>"$LOG"
}

# /usr/bin/time -v's figures: elapsed seconds and peak resident MB.
time_v() {
  awk -F': ' '/Elapsed \(wall clock\)/ { n = split($2, t, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + t[i]; el = s }
    /Maximum resident set size/ { rss = $2 / 1024 } END { printf "%.0f %.0f\n", el, rss }' "$1"
}

pyramid() { # the 32k mosaic and its pyramid under $OUT/big, made once
  if [ ! -f "$OUT/big-pyramid/pyramid.toml" ] || [ -z "${COMPARED[pyramid]:-}" ]; then
    if [ ! -d "$OUT/big" ]; then python3 scripts/make-large-mosaic.py "$OUT/big" 32 1024 >>"$LOG" 2>&1; fi
    rm -rf "$OUT/big-pyramid"
    /usr/bin/time -v -o "$OUT/tiles-time.txt" "$BIN" tiles "$OUT/big/*.png" --out-dir "$OUT/big-pyramid" \
      --height-scale 0.1 >>"$LOG" 2>&1
    COMPARED[pyramid]=1
  fi
}

table-tiles-convert() {
  head_line tiles-convert
  pyramid
  local el rss
  read -r el rss <<<"$(time_v "$OUT/tiles-time.txt")"
  echo '| source | time | peak resident memory | pyramid | levels | tiles |'
  echo '|---|---|---|---|---|---|'
  echo "| 32,768² mosaic, 1,024 PNG tiles ($(du -sh "$OUT/big" | cut -f1)) | $el s | $rss MB | $(du -sh "$OUT/big-pyramid" | cut -f1) | $(find "$OUT/big-pyramid" -maxdepth 1 -name 'L*' | wc -l) | $(find "$OUT/big-pyramid" -name '*.tile' | wc -l) |"
}

table-stream-flight() {
  head_line stream-flight
  pyramid
  local scene=$OUT/big.toml
  cat >"$scene" <<EOF
[sketch]
path = "big-pyramid"

[camera]
position = [491520.0, 300000.0, 7600.0]
look_at = [491520.0, 330000.0, 3000.0]
width = 480
height = 270

[path]
speed_mps = 400.0
keys = [
  { position = [491520.0, 300000.0, 7600.0], look_at = [491520.0, 330000.0, 3000.0] },
  { position = [491520.0, 340000.0, 7600.0], look_at = [491520.0, 370000.0, 3000.0] },
]
EOF
  local k rows=()
  for k in warped geomipmap reference settle; do
    local -a args=()
    case $k in
      geomipmap | reference) args=(--mode "$k") ;;
      settle) args=(--settle) ;;
    esac
    local dir=$OUT/fly/big-$k
    rm -rf "$dir"
    /usr/bin/time -v -o "$dir.time" "$BIN" fly "$scene" --out-dir "$dir" --frames 200 --no-mp4 --json "${args[@]+"${args[@]}"}" \
      >"$dir.json" 2>>"$LOG"
    local el rss
    read -r el rss <<<"$(time_v "$dir.time")"
    local cache
    cache=$(csv_stats "$dir/frames.csv" stream_us)
    rows+=("$(jq -r --arg el "$el" --arg rss "$rss" --arg cache "$cache" '"\(.gpu_memory_bytes / 1e6 | round) MB|\($rss) MB|\(.frame_ms_median | round) / \(.frame_ms_p95 | round) ms|\(.stream.tiles_loaded_mean | fx(2)) / \(.stream.tiles_loaded_max)|\(.stream.stand_in_frames) of 200|\($cache | split(" ") | "\(.[0]) / \(.[1]) µs")|\($el) s"' "$dir.json")")
  done
  echo '| figure | warped | GeoMipMap (`--mode geomipmap`) | reference (`--mode reference`) | warped, `--settle` |'
  echo '|---|---|---|---|---|'
  local i label
  local labels=('GPU memory (`gpu_memory_bytes`)' 'peak resident memory' 'frame time, median / p95' 'tiles loaded per frame, mean / max' 'frames that showed a stand-in' "the cache's own time per frame, median / p95" 'the whole flight')
  for i in "${!labels[@]}"; do
    label="| ${labels[$i]} |"
    for k in 0 1 2 3; do
      label="$label $(cut -d'|' -f$((i + 1)) <<<"${rows[$k]}") |"
    done
    echo "$label"
  done
}

# The relief measure (docs/picture.md): SKETCH seen straight down through the default framing
# at a 20° field of view, the sun at 315° and 45°, shadows off; extra arguments follow.
relief_r() {
  local sketch=$1 name=$2
  shift 2
  terrain render "$sketch" -o "$OUT/relief-$name.png" --size 512 --positions "$OUT/relief-$name.npy" --json \
    --set camera.pitch_deg=-90 --set camera.fov_y_deg=20 --set light.sun_azimuth_deg=315 \
    --set light.sun_elevation_deg=45 --set render.shadows=false "$@" | jq -r '.relief_r | fx(3)'
}

table-relief() {
  head_line relief
  echo '| sketch | relief r, natural | with `detail.octaves = 0` |'
  echo '|---|---|---|'
  local s name
  for s in gaussian hills ridges cliff; do
    printf '[sketch]\nsynthetic = "%s"\n' "$s" >"$OUT/relief-$s.toml"
  done
  for s in sketches/jacksboro_fault_dem.asc "$OUT"/relief-{gaussian,hills,ridges,cliff}.toml \
    tests/data/surface/jacksboro-utm.tif tests/data/surface/coast-4326.tif; do
    name=$(basename "$s" | sed 's/\.[a-z]*$//')
    echo "| $name | $(relief_r "$s" "$name") | $(relief_r "$s" "$name-0" --set detail.octaves=0) |"
  done
}

table-pictures() {
  head_line pictures
  local d=docs/pictures/gallery v
  # Links relative to docs/evaluation.md, where the table goes.
  local l=pictures/gallery
  mkdir -p "$d"
  echo '| picture | command |'
  echo '|---|---|'
  for v in "${VIEWS[@]}"; do
    terrain render "sketches/$v.toml" -o "$d/$v.jpg" --size 320 >/dev/null
    echo "| ![$v]($l/$v.jpg) | \`terrain render sketches/$v.toml -o $d/$v.jpg --size 320\` |"
  done
  local dem name
  for dem in tests/data/surface/jacksboro-utm.tif tests/data/surface/coast-4326.tif; do
    name=$(basename "$dem" .tif)
    terrain render "$dem" -o "$d/user-$name.jpg" --size 480x270 >/dev/null
    echo "| ![$name]($l/user-$name.jpg) | \`terrain render $dem -o $d/user-$name.jpg --size 480x270\` |"
    terrain render "$dem" -o "$d/user-$name-ramp.jpg" --size 480x270 --set surface.style='"ramp"' >/dev/null
    echo "| ![$name, hypsometric ramp]($l/user-$name-ramp.jpg) | \`terrain render $dem -o $d/user-$name-ramp.jpg --size 480x270 --set surface.style='\"ramp\"'\` |"
  done
  terrain render tests/data/surface/jacksboro-utm.tif -o "$d/user-jacksboro-utm-image.jpg" --size 480x270 \
    --set surface.image='"tests/data/surface/ortho-4326.tif"' >/dev/null
  echo "| ![jacksboro-utm with an image in EPSG:4326]($l/user-jacksboro-utm-image.jpg) | \`terrain render tests/data/surface/jacksboro-utm.tif -o $d/user-jacksboro-utm-image.jpg --size 480x270 --set surface.image='\"tests/data/surface/ortho-4326.tif\"'\` |"
  terrain render sketches/jacksboro-high.toml -o "$d/jacksboro-high-viridis.jpg" --size 320 \
    --set surface.color_ramp='"viridis"' >/dev/null
  echo "| ![viridis]($l/jacksboro-high-viridis.jpg) | \`terrain render sketches/jacksboro-high.toml -o $d/jacksboro-high-viridis.jpg --size 320 --set surface.color_ramp='\"viridis\"'\` |"
  terrain render tests/data/surface/jacksboro-utm.tif -o "$d/user-jacksboro-utm-gdal-ramp.jpg" --size 480x270 \
    --set surface.color_ramp='"tests/data/surface/ramp.txt"' >/dev/null
  echo "| ![gdaldem's example ramp]($l/user-jacksboro-utm-gdal-ramp.jpg) | \`terrain render tests/data/surface/jacksboro-utm.tif -o $d/user-jacksboro-utm-gdal-ramp.jpg --size 480x270 --set surface.color_ramp='\"tests/data/surface/ramp.txt\"'\` |"
}

# ---------------------------------------------------------------------------------------------

# The tables on stdout; how long each took on stderr, after each and together at the end.
TIMES=()
for t in "${WANTED[@]}"; do
  start=$(date +%s)
  "table-$t"
  TIMES+=("$t: $(($(date +%s) - start)) s")
  echo "evaluate.sh: ${TIMES[-1]}" >&2
done
{
  echo
  echo "Time per table${ADAPTER:+ ($ADAPTER)}:"
  printf '  %s\n' "${TIMES[@]}"
} >&2
