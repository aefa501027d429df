#!/usr/bin/env bash
# Regenerates tests/data/peer_values.json with the pinned peer libraries (see
# tests/data/README.md):
#
#   bash validation/peers/generate_peer_values.sh           # check, then write the file
#   bash validation/peers/generate_peer_values.sh --check   # check only; exit 1 if the file would change
#   bash validation/peers/generate_peer_values.sh --rough-interface [--check]
#       # the same venv, then validation/peers/generate_rough_interface_values.py, which writes
#       # tests/data/rough_interface_peer.json
#
# Uses the venv and wheel cache of validation/peers/run.sh (target/peers-venv, target/peers-wheels): needs
# PyPI on the first run, and compiles pySCATMECH from source there (about 6-10 minutes). Not part
# of CI; `cargo test` reads only the committed JSON.
set -euo pipefail

# The workspace root (this script is validation/peers/generate_peer_values.sh).
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
OUT="target/peers"
VENV="target/peers-venv"
WHEELS="target/peers-wheels"
mkdir -p "$OUT" "$WHEELS"

# Pinned versions (the same as validation/peers/run.sh; the script checks them again).
NUMPY="numpy==2.4.6"
PYPOL="py-pol==1.3.0"
MITSUBA="mitsuba==3.9.1"
DRJIT="drjit==1.5.0"
SCATMECH_VER="0.1.10"

export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 NUMEXPR_NUM_THREADS=1
export PYTHONDONTWRITEBYTECODE=1

[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
PY="$VENV/bin/python"
"$PY" -m pip install -q --disable-pip-version-check "$NUMPY" "$PYPOL" "$MITSUBA" "$DRJIT"

if ! "$PY" -c 'import SCATPY' 2>/dev/null; then
    WHL="$(ls "$WHEELS"/pyscatmech-"$SCATMECH_VER"-*.whl 2>/dev/null | head -1 || true)"
    if [ -z "$WHL" ]; then
        echo "== building pySCATMECH $SCATMECH_VER from source (first run only, several minutes;" \
            "log: $OUT/pyscatmech-build.log)"
        "$PY" -m pip wheel --disable-pip-version-check --no-deps -w "$WHEELS" \
            "pySCATMECH==$SCATMECH_VER" > "$OUT/pyscatmech-build.log" 2>&1
        WHL="$(ls "$WHEELS"/pyscatmech-"$SCATMECH_VER"-*.whl | head -1)"
    fi
    "$PY" -m pip install -q --disable-pip-version-check "$WHL"
fi

GENERATOR=validation/peers/generate_peer_values.py
if [ "${1:-}" = "--rough-interface" ]; then
    shift
    GENERATOR=validation/peers/generate_rough_interface_values.py
fi
exec "$PY" "$GENERATOR" "$@"
