#!/usr/bin/env bash
# Bearing accuracy on muTrack-style real captures (issue 54): one pcap per (trace, AP) and a
# truth CSV with one row per pair (columns file, ap, trace, expected_aoa_deg; see
# /work/shared/data/mutrack/README.md). Each pcap is imported (csi-import, cached in WORK and
# redone when csi-import is newer), csi-bearings runs on it with the given array, calibration and
# options, and the bearings are compared with expected_aoa_deg.
#
#   scripts/mutrack-eval.sh --array A.yaml --calib 'CAL/AP{ap}' [options] [-- csi-bearings options]
#
#   --data DIR       the captures' folder (default /work/shared/data/mutrack)
#   --truth CSV      truth table (default DIR/truth_D1.csv)
#   --array FILE     receive array file or shipped name (the muTrack APs: rt-ac86u-3core-57mm,
#                    cores: [0, 1, 3])
#   --calib PATTERN  calibration file or folder for csi-bearings --calib; "{ap}" is replaced by
#                    the AP number of the truth row (each AP has its own chain offsets)
#   --traces SET     odd | even | all | a comma-separated list of trace numbers (default all)
#   --aps LIST       comma-separated AP numbers (default: every AP of the truth table)
#   --algo NAME      csi-bearings --algo (default: the program's default estimator)
#   --label TEXT     name of this run (default: the algo); results in WORK/LABEL/
#   --build DIR      build directory with bin/ (default: the repository's build/)
#   --work DIR       scratch directory (default /tmp/mutrack-eval)
#   --pairs-csv F    also write the per-pair table as CSV
#   --rawlogs DIR    take DIR/<pcap name>.rawlog (already imported) instead of importing
#   --quiet-pairs    summary only (no per-pair lines)
# Everything after "--" goes to csi-bearings unchanged (e.g. -- -p window=16 --tracking off).
# A plain Bartlett baseline (one frame, one wavelength): --algo aoa_only --label bartlett --
# -p window=1 -p frequency_groups=1 (aoa_only is the project's Bartlett scan).
#
# Printed: per (trace, AP) the number of bearings, the per-trace median bearing and its |error|
# against expected_aoa_deg, and per packet the median |error|, % beyond 30 deg and % within 3
# sigma; then over the pairs (all, and per AP): median of the per-trace |error|, % of pairs
# beyond 20 deg, and the per-packet figures pooled over every bearing. A pair that gives no
# bearing counts as beyond 20 deg (error 180 in the median). Angles are the linear array's
# front-half-plane candidates (within +-90 deg of broadside), as is the truth: |error| is their
# plain difference. Needs bash and python3 (standard library only). Exit status 1 on a failure
# of csi-import or csi-bearings (named), 0 otherwise.
set -euo pipefail

src=$(cd "$(dirname "$0")/.." && pwd)
data=/work/shared/data/mutrack
truth=""
array=""
calib=""
traces=all
aps=""
algo=""
label=""
build="$src/build"
work=/tmp/mutrack-eval
pairsCsv=""
rawlogs=""
quietPairs=0
extra=()
while [ $# -gt 0 ]; do
  case "$1" in
    --data) data=$2; shift 2 ;;
    --truth) truth=$2; shift 2 ;;
    --array) array=$2; shift 2 ;;
    --calib) calib=$2; shift 2 ;;
    --traces) traces=$2; shift 2 ;;
    --aps) aps=$2; shift 2 ;;
    --algo) algo=$2; shift 2 ;;
    --label) label=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --pairs-csv) pairsCsv=$2; shift 2 ;;
    --rawlogs) rawlogs=$2; shift 2 ;;
    --quiet-pairs) quietPairs=1; shift ;;
    --) shift; extra=("$@"); break ;;
    -h|--help) sed -n '2,36p' "$0"; exit 0 ;;
    *) echo "mutrack-eval: unknown option '$1' (--help lists them)" >&2; exit 1 ;;
  esac
done
[ -n "$truth" ] || truth="$data/truth_D1.csv"
[ -f "$truth" ] || { echo "mutrack-eval: no truth table '$truth'" >&2; exit 1; }
[ -n "$array" ] || { echo "mutrack-eval: --array FILE is required" >&2; exit 1; }
# A shipped array by name (share/arrays/NAME.yaml), as csi-bearings --array takes it.
[ -f "$array" ] || [ ! -f "$src/share/arrays/$array.yaml" ] || array="$src/share/arrays/$array.yaml"
[ -f "$array" ] || { echo "mutrack-eval: no array file '$array'" >&2; exit 1; }
[ -n "$label" ] || label=${algo:-default}
importer="$build/bin/csi-import"
bearings="$build/bin/csi-bearings"
for b in "$importer" "$bearings"; do
  [ -x "$b" ] || { echo "mutrack-eval: '$b' not built" >&2; exit 1; }
done
mkdir -p "$work/rawlog" "$work/$label"

# The (file, ap, trace, expected) rows selected.
selected=$(python3 - "$truth" "$traces" "$aps" <<'EOF'
import csv, sys
path, traces, aps = sys.argv[1:4]
rows = list(csv.DictReader(open(path)))
for need in ("file", "ap", "trace", "expected_aoa_deg"):
    if rows and need not in rows[0]:
        sys.exit(f"mutrack-eval: {path} has no column '{need}'")
def keep_trace(t):
    t = int(t)
    if traces == "all": return True
    if traces == "odd": return t % 2 == 1
    if traces == "even": return t % 2 == 0
    return t in {int(x) for x in traces.split(",") if x}
want_aps = {int(x) for x in aps.split(",") if x}
for r in rows:
    if keep_trace(r["trace"]) and (not want_aps or int(r["ap"]) in want_aps):
        print(r["file"], r["ap"], r["trace"], r["expected_aoa_deg"])
EOF
)
[ -n "$selected" ] || { echo "mutrack-eval: no (trace, AP) selected" >&2; exit 1; }

algoOpt=()
[ -n "$algo" ] && algoOpt=(--algo "$algo")
status=0
while read -r file ap trace expected; do
  pcap="$data/$file"
  base=$(basename "$file" .pcap)
  raw="$work/rawlog/$base.rawlog"
  if [ -n "$rawlogs" ]; then
    raw="$rawlogs/$base.rawlog"
    [ -f "$raw" ] || { echo "mutrack-eval: missing rawlog '$raw'" >&2; status=1; continue; }
  elif [ ! -f "$pcap" ]; then
    echo "mutrack-eval: missing capture '$pcap'" >&2; status=1; continue
  elif [ ! -f "$raw" ] || [ "$importer" -nt "$raw" ] || [ "$pcap" -nt "$raw" ]; then
    rc=0
    nice "$importer" "$pcap" "$raw" >"$work/rawlog/$base.import.log" 2>&1 || rc=$?
    # 3: records skipped but the file finished (csi-import's documented status).
    if [ $rc -ne 0 ] && [ $rc -ne 3 ]; then
      echo "mutrack-eval: csi-import failed ($rc) on $pcap: $(tail -n 2 "$work/rawlog/$base.import.log")" >&2
      rm -f "$raw"; status=1; continue
    fi
  fi
  cal=()
  [ -n "$calib" ] && cal=(--calib "${calib//\{ap\}/$ap}")
  out="$work/$label/$base"
  if ! nice "$bearings" "$raw" "$out.rawlog" --array "$array" "${cal[@]}" "${algoOpt[@]}" \
      --csv "$out.csv" -q "${extra[@]}" >"$out.log" 2>&1; then
    echo "mutrack-eval: csi-bearings failed on $raw: $(tail -n 3 "$out.log")" >&2
    : >"$out.csv"; echo "FAILED" >>"$out.log"
  fi
  rm -f "$out.rawlog"
done <<<"$selected"

SELECTED="$selected" python3 - "$work/$label" "$quietPairs" "$pairsCsv" "$label" <<'EOF' || status=1
import csv, math, os, statistics, sys
outdir, quiet, pairs_csv, label = sys.argv[1], sys.argv[2] == "1", sys.argv[3], sys.argv[4]
selected = os.environ["SELECTED"].strip().splitlines()

def load(path):
    """Bearings of the transmitter heard most in one csi-bearings CSV: (aoa, std) in degrees."""
    by_tx = {}
    if os.path.exists(path) and os.path.getsize(path) > 0:
        for r in csv.DictReader(open(path)):
            if r["aoa_deg"] == "": continue
            by_tx.setdefault(r["transmitter"], []).append(
                (float(r["aoa_deg"]), float(r["aoa_std_deg"])))
    if not by_tx: return [], 0
    tx = max(by_tx, key=lambda k: len(by_tx[k]))
    return by_tx[tx], len(by_tx) - 1

def pct(a, b): return 100.0 * a / b if b else float("nan")

pairs = []
for line in selected:
    file, ap, trace, expected = line.split()
    base = os.path.splitext(os.path.basename(file))[0]
    b, others = load(os.path.join(outdir, base + ".csv"))
    truth = float(expected)
    errs = [abs(a - truth) for a, _ in b]
    p = {"ap": int(ap), "trace": int(trace), "truth": truth, "n": len(b), "others": others,
         "errs": errs, "within3": sum(1 for (a, s) in b if abs(a - truth) <= 3 * s)}
    if b:
        p["median"] = statistics.median(a for a, _ in b)
        p["err"] = abs(p["median"] - truth)
        p["pkt_median"] = statistics.median(errs)
        p["beyond30"] = pct(sum(e > 30 for e in errs), len(errs))
        p["in3"] = pct(p["within3"], len(errs))
        p["median_std"] = statistics.median(s for _, s in b)
    else:
        p.update(median=float("nan"), err=float("nan"), pkt_median=float("nan"),
                 beyond30=float("nan"), in3=float("nan"), median_std=float("nan"))
    pairs.append(p)

pairs.sort(key=lambda p: (p["ap"], p["trace"]))
if not quiet:
    print(f"{'AP':>3} {'tr':>3} {'truth':>7} {'n':>5} {'median':>7} {'|err|':>6} "
          f"{'pkt med':>7} {'>30%':>6} {'<=3s%':>6} {'med s':>6}")
    for p in pairs:
        print(f"{p['ap']:>3} {p['trace']:>3} {p['truth']:7.2f} {p['n']:5d} {p['median']:7.2f} "
              f"{p['err']:6.2f} {p['pkt_median']:7.2f} {p['beyond30']:6.1f} {p['in3']:6.1f} "
              f"{p['median_std']:6.1f}" + ("  (no bearings)" if not p["n"] else "")
              + (f"  ({p['others']} other transmitters ignored)" if p["others"] else ""))

def summary(name, ps):
    errs = [p["err"] if p["n"] else 180.0 for p in ps]
    pk = [e for p in ps for e in p["errs"]]
    in3 = sum(p["within3"] for p in ps)
    empty = sum(1 for p in ps if not p["n"])
    print(f"{label:>10} {name:>4}: pairs {len(ps):3d} (no bearings {empty}), per-trace median "
          f"|error| {statistics.median(errs):5.2f} deg, beyond 20 deg {pct(sum(e > 20 for e in errs), len(errs)):5.1f} %"
          f" | per packet ({len(pk)}): median {statistics.median(pk) if pk else float('nan'):5.2f} deg, "
          f"beyond 30 deg {pct(sum(e > 30 for e in pk), len(pk)):5.1f} %, within 3 sigma {pct(in3, len(pk)):5.1f} %")

print()
summary("all", pairs)
for ap in sorted({p["ap"] for p in pairs}):
    summary(f"AP{ap}", [p for p in pairs if p["ap"] == ap])
worst = sorted((p for p in pairs), key=lambda p: -(p["err"] if p["n"] else 180.0))[:5]
print("worst pairs: " + ", ".join(
    f"tr{p['trace']} AP{p['ap']} {p['err']:.1f} deg (median {p['median']:.1f}, truth {p['truth']:.1f})"
    for p in worst))
if pairs_csv:
    with open(pairs_csv, "w") as f:
        f.write("ap,trace,truth_deg,bearings,median_deg,error_deg,packet_median_error_deg,"
                "beyond30_pct,within3sigma_pct,median_std_deg\n")
        for p in pairs:
            f.write(f"{p['ap']},{p['trace']},{p['truth']},{p['n']},{p['median']:.3f},{p['err']:.3f},"
                    f"{p['pkt_median']:.3f},{p['beyond30']:.2f},{p['in3']:.2f},{p['median_std']:.3f}\n")
EOF
exit $status
