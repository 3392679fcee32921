#!/usr/bin/env bash
# Every bundled view in every mode it draws, on a GPU, in one run sized to end within 8 minutes:
# the figures of docs/evaluation.md, GPU costs, for a machine with a GPU but perhaps no network and
# no Rust toolchain. It runs a release `terrain` built elsewhere and copied beside `sketches/`.
#
#   scripts/gpu-bench.sh [--out DIR] [--quick] [--allow-software] [--scenes A,B…] [--sizes WxH,…]
#                        [--repeat N] [--compare-repeat N] [--path-frames N] [--budget S] [--images]
#
# The folder above scripts/ holds `terrain` (else target/release/terrain; TERRAIN_BIN names
# another) and sketches/. Per view and mode, at 512² and 1920×1080, `terrain render VIEW --mode M
# --size WxH --repeat 30 --json`; then per view `terrain compare VIEW --out-dir DIR --repeat 10
# --path-frames 12` (the default sweep at 256²). Into --out (default gpu-bench-DATE):
#   frames.csv     one row per view × mode × size: adapter, samples, triangles, the medians of
#                  gpu_ms, frame_ms, cpu_stage_us and of every pass (pass_NAME_ms)
#   compare/VIEW/  each compare's report.csv, report.json, summary.md and figures
#   json/, logs/   each command's JSON and its stderr; machine.txt: the adapter, date and build
#   failures.txt   the steps that failed or were skipped; the script then exits 1
# Views: jacksboro, gaussian and hills with their -high twins (warped, geomipmap, bruteforce,
# reference), and planet-orbit, planet-10km and planet-ground (clipmaps, reference).
#
# --allow-software  measure a software rasteriser (llvmpipe, lavapipe, SwiftShader, WARP) too;
#                   without it the script refuses one, since its times are the CPU's
# --quick           a check of the script on a CPU: 64x64 and 64x36, 1 frame, compares at 64²
#                   with 1 frame per setting, no path, warped and geomipmap (a planet's clipmaps)
# --budget S        start no step after S seconds (default 420; --quick none), so that a slower
#                   machine still ends near 8 minutes; the steps left out go to failures.txt
# --images          keep every rendered frame under images/ (else one scratch file is rewritten)
#
# Needs bash 4+ and python3 (to read terrain's JSON). One failing step does not stop the others.
set -euo pipefail

usage() { sed -n '2,29p' "$0" | sed 's/^# \{0,1\}//'; }
die() {
  echo "gpu-bench.sh: $*" >&2
  exit 2
}

ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=
QUICK=0
ALLOW_SOFTWARE=0
SCENES=
SIZES=
REPEAT=
COMPARE_REPEAT=
PATH_FRAMES=
BUDGET=
IMAGES=0

while [ $# -gt 0 ]; do
  case $1 in
    --out) OUT=${2:?--out needs a folder}; shift ;;
    --quick) QUICK=1 ;;
    --allow-software) ALLOW_SOFTWARE=1 ;;
    --scenes) SCENES=${2:?--scenes needs a comma-separated list}; shift ;;
    --sizes) SIZES=${2:?--sizes needs a comma-separated list of WxH}; shift ;;
    --repeat) REPEAT=${2:?--repeat needs a number}; shift ;;
    --compare-repeat) COMPARE_REPEAT=${2:?--compare-repeat needs a number}; shift ;;
    --path-frames) PATH_FRAMES=${2:?--path-frames needs a number}; shift ;;
    --budget) BUDGET=${2:?--budget needs seconds}; shift ;;
    --images) IMAGES=1 ;;
    -h | --help) usage; exit 0 ;;
    *) echo "gpu-bench.sh: unknown argument $1" >&2; usage >&2; exit 2 ;;
  esac
  shift
done

if [ "$QUICK" = 1 ]; then
  : "${SIZES:=64x64,64x36}" "${REPEAT:=1}" "${COMPARE_REPEAT:=1}" "${PATH_FRAMES:=0}" "${BUDGET:=0}"
  COMPARE_SIZE=64
else
  : "${SIZES:=512x512,1920x1080}" "${REPEAT:=30}" "${COMPARE_REPEAT:=10}" "${PATH_FRAMES:=12}" "${BUDGET:=420}"
  COMPARE_SIZE=256
fi
for n in "$REPEAT" "$COMPARE_REPEAT" "$PATH_FRAMES" "$BUDGET"; do
  [[ $n =~ ^[0-9]+$ ]] || die "$n is not a whole number"
done
IFS=, read -r -a SIZE_LIST <<<"$SIZES"
for s in "${SIZE_LIST[@]}"; do
  [[ $s =~ ^[0-9]+x[0-9]+$ ]] || die "size $s is not WxH"
done

command -v python3 >/dev/null || die "needs python3 to read terrain's JSON (Debian: apt-get install python3-minimal)"

# Paths given on the command line are the caller's; everything else is the root's.
[ -n "$OUT" ] || OUT=gpu-bench-$(date +%Y-%m-%d-%H%M)
OUT=$(realpath -m -- "$OUT")
if [ -n "${TERRAIN_BIN:-}" ]; then
  BIN=$(realpath -m -- "$TERRAIN_BIN")
elif [ -x "$ROOT/terrain" ]; then
  BIN=$ROOT/terrain
else
  BIN=$ROOT/target/release/terrain
fi
if [ -n "$SCENES" ]; then
  IFS=, read -r -a VIEWS <<<"$SCENES"
  for i in "${!VIEWS[@]}"; do
    case ${VIEWS[$i]} in *.toml) VIEWS[i]=$(realpath -m -- "${VIEWS[$i]}") ;; esac
  done
else
  VIEWS=(jacksboro jacksboro-high gaussian gaussian-high hills hills-high planet-orbit planet-10km planet-ground)
fi
cd "$ROOT"
[ -x "$BIN" ] || die "no terrain binary at $BIN: copy a release build (cargo build --release; target/release/terrain) there, or name it in TERRAIN_BIN"
[ -d sketches ] || die "no sketches/ folder in $ROOT: copy the repository's sketches/ beside scripts/"

# A view is NAME (sketches/NAME.toml) or a scene file; its name keys the output files.
scene_of() { case $1 in *.toml) printf '%s' "$1" ;; *) printf 'sketches/%s.toml' "$1" ;; esac; }
name_of() { local b; b=$(basename -- "$1"); printf '%s' "${b%.toml}"; }
for v in "${VIEWS[@]}"; do
  [ -f "$(scene_of "$v")" ] || die "no scene $(scene_of "$v")"
done
# The modes a view draws, from the binary's mode table (`terrain modes --json`): a planet's
# (clipmaps and the reference), or a plane's (warped, GeoMipMap, brute force, the reference).
MODES_JSON=$("$BIN" modes --json) || die "$BIN modes --json failed: a terrain binary older than its scripts?"
modes_of() {
  local kind=flat
  grep -q '^\[planet\]' "$(scene_of "$1")" && kind=planet
  python3 -c 'import json, sys
print(" ".join(m["name"] for m in json.loads(sys.argv[1])["modes"] if m["scenes"] in (sys.argv[2], "both")))' "$MODES_JSON" "$kind"
}

if [ -d "$OUT" ] && [ -n "$(ls -A -- "$OUT")" ]; then
  die "$OUT is not empty: name a new folder with --out"
fi
SCRATCH=$(mktemp -d)
trap 'rm -rf -- "$SCRATCH"' EXIT

# JSON, read by python3: `adapter FILE`, `summary FILE` (one line of a frame's figures) and
# `frames RUNS.tsv OUT.csv` (frames.csv from each run's JSON, in the order they ran).
PY=$(
  cat <<'EOF'
import csv, json, sys

def load(path):
    with open(path) as f:
        return json.load(f)

def ms(x):
    return "" if x is None else f"{x:.4f}"

def ratio(v):
    return "" if v is None else f"{v:.3f}"

cmd = sys.argv[1]
if cmd == "adapter":
    print(load(sys.argv[2])["adapter"])
elif cmd == "summary":
    j = load(sys.argv[2])
    print(f"GPU {ms(j.get('gpu_ms'))} ms, frame {ms(j.get('frame_ms'))} ms, "
          f"{j['triangles']:,} triangles, {j['samples']} samples, median of {j['frames']}")
elif cmd == "frames":
    runs = []
    with open(sys.argv[2]) as f:
        for line in f:
            scene, path = line.rstrip("\n").split("\t")
            runs.append((scene, load(path)))
    passes = []
    for _, j in runs:
        for p in j.get("passes_ms") or {}:
            if p not in passes:
                passes.append(p)
    fixed = ["adapter", "scene", "mode", "width", "height", "samples", "deferred", "triangles",
             "frames", "gpu_ms", "frame_ms", "cpu_stage_us", "gpu_wall_ms", "gpu_timing",
             "gpu_memory_bytes", "covered_px", "fragments_per_covered_px"]
    with open(sys.argv[3], "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(fixed + [f"pass_{p}_ms" for p in passes])
        for scene, j in runs:
            w.writerow([j["adapter"], scene, j["mode"], j["width"], j["height"], j["samples"],
                        str(j["deferred"]).lower(), j["triangles"], j["frames"], ms(j["gpu_ms"]),
                        ms(j["frame_ms"]), f"{j['cpu_stage_us']:.1f}", ms(j.get("gpu_wall_ms")),
                        j.get("gpu_timing", ""), j.get("gpu_memory_bytes", ""),
                        j.get("covered_px", ""), ratio(j.get("fragments_per_covered_px"))]
                       + [ms((j.get("passes_ms") or {}).get(p)) for p in passes])
EOF
)
py() { python3 -c "$PY" "$@"; }

# Microseconds since the epoch (EPOCHREALTIME's decimal point follows the locale).
now_us() {
  local t=${EPOCHREALTIME:-}
  if [ -n "$t" ]; then echo "${t/[.,]/}"; else echo $(($(date +%s%N) / 1000)); fi
}
secs() { printf '%d.%d' $(($1 / 1000000)) $(($1 % 1000000 / 100000)); }
START=$(now_us)
elapsed() { secs $(($(now_us) - START)); }
over_budget() { [ "$BUDGET" -gt 0 ] && [ $(($(now_us) - START)) -ge $((BUDGET * 1000000)) ]; }

# A step's command with its stdout to $1 and stderr to $2; a hung one is stopped after 5 minutes.
LIMIT=()
command -v timeout >/dev/null && LIMIT=(timeout 300)
step() {
  local out=$1 err=$2
  shift 2
  "${LIMIT[@]}" "$BIN" "$@" >"$out" 2>"$err"
}
failed() {
  local what=$1 rc=$2 err=$3 why
  why=$(tr '\r' '\n' <"$err" | grep -v '^\s*$' | tail -1 || true)
  echo "$what: exit $rc: ${why:-no message}" >>"$OUT/failures.txt"
  printf '%8s s  FAILED %s (exit %s): %s\n' "$(elapsed)" "$what" "$rc" "${why:-no message}"
}

# The adapter, from one small frame of the first view; a software rasteriser is refused.
rc=0
step "$SCRATCH/probe.json" "$SCRATCH/probe.err" render "$(scene_of "${VIEWS[0]}")" \
  -o "$SCRATCH/probe.png" --size 64 --json || rc=$?
if [ "$rc" != 0 ]; then
  echo "gpu-bench.sh: terrain could not render on this machine (exit $rc):" >&2
  tail -5 "$SCRATCH/probe.err" >&2
  exit 1
fi
ADAPTER=$(py adapter "$SCRATCH/probe.json")
echo "adapter: $ADAPTER"
shopt -s nocasematch
if [[ $ADAPTER =~ (llvmpipe|lavapipe|softpipe|swiftshader|basic\ render\ driver|(^|[^a-z])warp([^a-z]|$)) ]] &&
  [ "$ALLOW_SOFTWARE" = 0 ]; then
  echo "gpu-bench.sh: $ADAPTER is a software rasteriser, not a GPU (WGPU_BACKEND=vulkan asks for Vulkan's adapters); pass --allow-software to measure it anyway" >&2
  exit 1
fi
shopt -u nocasematch
mkdir -p "$OUT"/json "$OUT"/logs "$OUT"/compare
: >"$OUT/failures.txt"
: >"$SCRATCH/runs.tsv"
{
  echo "adapter: $ADAPTER"
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "terrain: $("$BIN" --version 2>/dev/null || echo unknown), $BIN"
  # A copy without .git may sit inside another repository, whose commit is not the build's.
  if [ -e "$ROOT/.git" ]; then
    echo "commit: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  fi
  if command -v nvidia-smi >/dev/null; then
    nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null | sed 's/^/gpu: /' || true
  fi
  echo "cpu: $(nproc) cores, $(awk -F': ' '/model name/ { print $2; exit }' /proc/cpuinfo 2>/dev/null || echo unknown)"
  echo "views: ${VIEWS[*]}"
  echo "frames: sizes $SIZES, --repeat $REPEAT; compare: --size $COMPARE_SIZE --repeat $COMPARE_REPEAT --path-frames $PATH_FRAMES"
} >"$OUT/machine.txt"

# Frames back to back: every view in every mode at every size.
[ "$IMAGES" = 1 ] && mkdir -p "$OUT/images"
for v in "${VIEWS[@]}"; do
  scene=$(scene_of "$v")
  name=$(name_of "$v")
  for mode in $(modes_of "$v"); do
    for size in "${SIZE_LIST[@]}"; do
      what="render $name $mode $size"
      key=$name-$mode-$size
      if over_budget; then
        echo "$what: skipped, past the ${BUDGET} s budget" >>"$OUT/failures.txt"
        printf '%8s s  skipped %s (past the %s s budget)\n' "$(elapsed)" "$what" "$BUDGET"
        continue
      fi
      image=$SCRATCH/frame.png
      [ "$IMAGES" = 1 ] && image=$OUT/images/$key.png
      t0=$(now_us)
      rc=0
      step "$OUT/json/$key.json" "$OUT/logs/$key.log" render "$scene" -o "$image" \
        --size "$size" --mode "$mode" --repeat "$REPEAT" --json || rc=$?
      if [ "$rc" = 0 ] && line=$(py summary "$OUT/json/$key.json" 2>>"$OUT/logs/$key.log"); then
        printf '%s\t%s\n' "$name" "$OUT/json/$key.json" >>"$SCRATCH/runs.tsv"
        printf '%8s s  %-40s %5s s  %s\n' "$(elapsed)" "$what" "$(secs $(($(now_us) - t0)))" "$line"
      else
        [ "$rc" != 0 ] || rc=unreadable
        failed "$what" "$rc" "$OUT/logs/$key.log"
      fi
    done
  done
done
if ! py frames "$SCRATCH/runs.tsv" "$OUT/frames.csv" 2>"$OUT/logs/frames-csv.log"; then
  failed "frames.csv" 1 "$OUT/logs/frames-csv.log"
fi

# One compare per view: the default sweep of every mode it draws against the reference.
for v in "${VIEWS[@]}"; do
  scene=$(scene_of "$v")
  name=$(name_of "$v")
  what="compare $name"
  if over_budget; then
    echo "$what: skipped, past the ${BUDGET} s budget" >>"$OUT/failures.txt"
    printf '%8s s  skipped %s (past the %s s budget)\n' "$(elapsed)" "$what" "$BUDGET"
    continue
  fi
  args=(--size "$COMPARE_SIZE" --repeat "$COMPARE_REPEAT" --path-frames "$PATH_FRAMES")
  if [ "$QUICK" = 1 ] && ! grep -q '^\[planet\]' "$scene"; then
    args+=(--modes "warped,geomipmap")
  fi
  t0=$(now_us)
  rc=0
  step "$OUT/logs/compare-$name.txt" "$OUT/logs/compare-$name.log" compare "$scene" \
    --out-dir "$OUT/compare/$name" "${args[@]}" || rc=$?
  if [ "$rc" = 0 ] && [ -s "$OUT/compare/$name/report.csv" ]; then
    rows=$(($(wc -l <"$OUT/compare/$name/report.csv") - 1))
    printf '%8s s  %-40s %5s s  %d settings\n' "$(elapsed)" "$what" "$(secs $(($(now_us) - t0)))" "$rows"
  else
    [ "$rc" != 0 ] || rc="no report.csv"
    failed "$what" "$rc" "$OUT/logs/compare-$name.log"
  fi
done

n=$(wc -l <"$OUT/failures.txt")
echo "$(elapsed) s in all; frames.csv, compare/ and machine.txt in $OUT"
if [ "$n" -gt 0 ]; then
  echo "gpu-bench.sh: $n step(s) failed or were skipped (failures.txt):" >&2
  cat "$OUT/failures.txt" >&2
  exit 1
fi
