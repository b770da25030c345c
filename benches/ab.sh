#!/usr/bin/env bash
# benches/ab.sh A_BIN B_BIN OUTDIR ROUNDS scene...
# Interleaved `haptloop bench` A/B of two binaries (e.g. main's and a branch's
# target/release/haptloop, copied aside), the order alternating by round; 20000
# ticks, 2000 for the large scenes. Prints per scene the median p50 tick without
# the device stages of A and B and the median (and range) of the per-round
# ratios B/A. BENCHMARKS.md's "same-run A/B" figures come from it.
set -euo pipefail
A=$1; B=$2; OUT=$3; R=$4; shift 4
mkdir -p "$OUT"
for r in $(seq 1 "$R"); do
  for s in "$@"; do
    case $s in lattice|cluttered|sphere-toy|chain|*400*) T=2000;; *) T=20000;; esac
    if [ $((r % 2)) -eq 1 ]; then order="A B"; else order="B A"; fi
    for w in $order; do
      bin=$A; [ "$w" = B ] && bin=$B
      "$bin" bench "$s" --ticks $T --json "$OUT/$s.$w.$r.json" >/dev/null 2>&1 || echo "FAIL $w $s $r"
    done
  done
done
python3 - "$OUT" "$R" "$@" <<'PY'
import json,sys,statistics as st
out,R,scenes=sys.argv[1],int(sys.argv[2]),sys.argv[3:]
for s in scenes:
    a=[];b=[];rat=[]
    for r in range(1,R+1):
        try:
            ja=json.load(open(f"{out}/{s}.A.{r}.json"));jb=json.load(open(f"{out}/{s}.B.{r}.json"))
        except Exception: continue
        pa=ja["tick_without_device_ns"]["p50"];pb=jb["tick_without_device_ns"]["p50"]
        a.append(pa);b.append(pb);rat.append(pb/pa)
    if rat: print(f"{s:14s} A {st.median(a)/1e3:9.2f} us  B {st.median(b)/1e3:9.2f} us  B/A {st.median(rat):.3f}  rounds {min(rat):.3f}-{max(rat):.3f}")
PY
