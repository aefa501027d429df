#!/usr/bin/env bash
# Peer-calibration harness: measures py-pol, pySCATMECH, Mitsuba 3 and a plain C++ closed form on
# this machine, single thread, and prints one table (see validation/peers/README.md).
#
#   bash validation/peers/run.sh            # everything
#   bash validation/peers/run.sh mitsuba    # only the Mitsuba scripts (mitsuba_*.py)
#
# Needs PyPI (and Debian's apt repository only if no libLLVM >= 17 is installed). Writes only under
# the workspace's target/ (venv target/peers-venv, wheels target/peers-wheels, binaries and results
# target/peers/). Not part of CI.
set -uo pipefail

MODE="${1:-all}"
case "$MODE" in
    all | mitsuba) ;;
    *) echo "usage: bash validation/peers/run.sh [mitsuba]" >&2; exit 2 ;;
esac

# The workspace root (this script is validation/peers/run.sh).
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
OUT="target/peers"
VENV="target/peers-venv"
WHEELS="target/peers-wheels"
mkdir -p "$OUT" "$WHEELS"
# A Mitsuba-only run writes its own rows and table, so that it leaves the full table alone.
if [ "$MODE" = mitsuba ]; then SUFFIX="-mitsuba"; else SUFFIX=""; fi
ROWS="$OUT/rows$SUFFIX.txt"
: > "$ROWS"

# Pinned versions.
PYPOL="py-pol==1.3.0"
NUMPY="numpy==2.4.6"
MITSUBA="mitsuba==3.9.1"
DRJIT="drjit==1.5.0"
SCATMECH_VER="0.1.10"

# Single thread everywhere.
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 NUMEXPR_NUM_THREADS=1
# No __pycache__ inside validation/peers/.
export PYTHONDONTWRITEBYTECODE=1

echo "== machine"
lscpu | grep -E '^(Model name|CPU family|Model|CPU\(s\)|Flags)' | sed -E 's/^(Flags:\s+).*/\1(avx2: '"$(grep -qw avx2 /proc/cpuinfo && echo yes || echo no)"', fma: '"$(grep -qw fma /proc/cpuinfo && echo yes || echo no)"', avx512f: '"$(grep -qw avx512f /proc/cpuinfo && echo yes || echo no)"')/'
echo "date: $(date -u '+%Y-%m-%d %H:%M UTC')"
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"

# --- LLVM for Mitsuba's llvm variants ---------------------------------------------------------
# Dr.Jit 1.5.0's LLVM back-end needs libLLVM >= 17: with Debian bookworm's libLLVM 15 and 16 its
# kernels fail to compile ("LLVM ERROR: Cannot select: fmaximum", seen 2026-12-04). Use the
# newest libLLVM installed; if it is older than 17, install Debian's libllvm19 (root only).
# Prints "major path" of the newest one (Debian names it libLLVM-15.so.1 up to 16,
# libLLVM.so.19.1 from 19 on).
newest_llvm() {
    ldconfig -p | grep -oE '/[^ ]*libLLVM(-[0-9]+)?\.so[.0-9]*$' \
        | sed -E 's/.*libLLVM(-([0-9]+)\.so|\.so\.([0-9]+)).*/\2\3 &/' \
        | grep -E '^[0-9]+ ' | sort -n | tail -1
}
read -r LLVM_MAJOR LLVM_LIB <<< "$(newest_llvm)"
if [ -z "$LLVM_LIB" ] || [ "${LLVM_MAJOR:-0}" -lt 17 ]; then
    echo "== libLLVM ${LLVM_MAJOR:-none} is too old for Dr.Jit 1.5: installing libllvm19 with apt-get"
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        apt-get install -y -qq libllvm19 >/dev/null 2>&1 \
            || { apt-get update -qq && apt-get install -y -qq libllvm19; } \
            || echo "apt-get install libllvm19 failed"
        read -r LLVM_MAJOR LLVM_LIB <<< "$(newest_llvm)"
    else
        echo "not root or no apt-get: the llvm variant may fail"
    fi
fi
if [ -n "$LLVM_LIB" ]; then export DRJIT_LIBLLVM_PATH="$LLVM_LIB"; fi
echo "libLLVM for Dr.Jit: ${DRJIT_LIBLLVM_PATH:-none}"

# --- Python environment -----------------------------------------------------------------------
echo "== venv $VENV"
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV" || { echo "venv creation failed"; exit 1; }
PY="$VENV/bin/python"
"$PY" -m pip install -q --disable-pip-version-check "$NUMPY" "$PYPOL" "$MITSUBA" "$DRJIT" \
    || { echo "pip install of py-pol/mitsuba failed"; exit 1; }

# pySCATMECH ships only an sdist: the first run compiles SCATMECH (~80 C++ files, one at a time,
# about 6 minutes here); the wheel is kept in target/peers-wheels for later runs.
SCATMECH_OK=1
if [ "$MODE" = mitsuba ]; then
    SCATMECH_OK=0  # not needed: neither built nor timed
elif ! "$PY" -c 'import SCATPY' 2>/dev/null; then
    WHL="$(ls "$WHEELS"/pyscatmech-"$SCATMECH_VER"-*.whl 2>/dev/null | head -1)"
    if [ -z "$WHL" ]; then
        echo "== building pySCATMECH $SCATMECH_VER from source (first run only, several minutes)"
        if "$PY" -m pip wheel --disable-pip-version-check --no-deps -w "$WHEELS" \
            "pySCATMECH==$SCATMECH_VER" > "$OUT/pyscatmech-build.log" 2>&1; then
            WHL="$(ls "$WHEELS"/pyscatmech-"$SCATMECH_VER"-*.whl | head -1)"
        else
            SCATMECH_OK=0
            ERR="$(grep -m3 -iE 'error' "$OUT/pyscatmech-build.log" | tr '\n' ' ' | cut -c1-300)"
            echo "ROW|pySCATMECH|Rayleigh-Rice Mueller BRDF|-|-|-|-|SKIPPED: pip wheel pySCATMECH==$SCATMECH_VER failed: $ERR (log: $OUT/pyscatmech-build.log)" >> "$ROWS"
        fi
    fi
    if [ "$SCATMECH_OK" = 1 ] && ! "$PY" -m pip install -q --disable-pip-version-check "$WHL"; then
        SCATMECH_OK=0
        echo "ROW|pySCATMECH|Rayleigh-Rice Mueller BRDF|-|-|-|-|SKIPPED: pip install of $WHL failed" >> "$ROWS"
    fi
fi

echo "== versions"
"$PY" - <<'EOF' | tee "$OUT/versions.txt"
import importlib.metadata as md, platform
print("python", platform.python_version())
for p in ["numpy", "scipy", "py-pol", "pySCATMECH", "mitsuba", "drjit"]:
    try:
        print(p, md.version(p))
    except md.PackageNotFoundError:
        print(p, "not installed")
EOF
echo "g++ $(g++ -dumpfullversion)" | tee -a "$OUT/versions.txt"

# --- Python peers -----------------------------------------------------------------------------
echo "== timing starts; load average: $(cut -d' ' -f1-3 /proc/loadavg) (other jobs on this machine inflate the medians)"
run_py() {
    echo "== $1"
    # OPENBLAS_CORETYPE / OPENBLAS_L2_SIZE (set on some machines here) slow numpy: unset them for
    # the benchmark command only.
    (cd validation/peers && env -u OPENBLAS_CORETYPE -u OPENBLAS_L2_SIZE "../../$PY" "$1") | tee -a "$ROWS" \
        || echo "ROW|$1|-|-|-|-|-|-|FAILED: see the output above" >> "$ROWS"
}
if [ "$MODE" = all ]; then run_py pypol_jones_mueller.py; fi
if [ "$SCATMECH_OK" = 1 ]; then run_py pyscatmech_rayleigh_rice.py; fi
run_py mitsuba_fresnel.py
run_py mitsuba_rough_conductor.py
run_py mitsuba_sample.py
run_py mitsuba_path.py

# --- C++ closed form --------------------------------------------------------------------------
if [ "$MODE" = all ]; then FLAVOURS="default native"; else FLAVOURS=""; fi
for flavour in $FLAVOURS; do
    if [ "$flavour" = native ]; then FLAGS="-O3 -march=native"; else FLAGS="-O3"; fi
    BIN="$OUT/jones_mueller_soa_$flavour"
    echo "== C++ g++ $FLAGS"
    if ! g++ $FLAGS -std=c++17 -Wall -Wextra validation/peers/jones_mueller_soa.cpp -o "$BIN"; then
        echo "ROW|C++ (g++ $FLAGS)|Jones->Mueller closed form, SoA|-|-|-|-|FAILED: build error" >> "$ROWS"
        continue
    fi
    if ! "$BIN" > "$OUT/cpp_$flavour.txt"; then
        echo "ROW|C++ (g++ $FLAGS)|Jones->Mueller closed form, SoA|-|-|-|-|FAILED: closed form disagrees with the literal 4x4 product" >> "$ROWS"
        continue
    fi
    cat "$OUT/cpp_$flavour.txt"
    while read -r prec layout n med lo _rest; do
        echo "ROW|C++ (g++ $FLAGS)|Jones->Mueller closed form, SoA, $layout streams|$prec|$n|$med|$lo|per matrix" >> "$ROWS"
    done < "$OUT/cpp_$flavour.txt"
done

# --- table ------------------------------------------------------------------------------------
echo
echo "== results (ns per item, single thread; median and min over repeated samples)"
"$PY" - "$ROWS" <<'EOF' | tee "$OUT/results$SUFFIX.md"
import sys
print("| peer | operation | precision | batch N | median ns/item | min ns/item | note |")
print("|---|---|---|---:|---:|---:|---|")
def num(s):
    try:
        x = float(s)
    except ValueError:
        return s
    return f"{x:.0f}" if x >= 100 else f"{x:.3g}"
for line in open(sys.argv[1]):
    if line.startswith("ROW|"):
        f = line.rstrip("\n").split("|")[1:]
        f += [""] * (7 - len(f))
        f[4], f[5] = num(f[4]), num(f[5])
        print("| " + " | ".join(f[:6] + ["|".join(f[6:])]) + " |")
EOF
echo "load average after timing: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "(table also in $OUT/results$SUFFIX.md)"
