#!/usr/bin/env python3
"""Generates tests/data/peer_values.json: reference values computed by peer libraries, each in that
library's own convention (see tests/data/README.md for the conversion rules).

    bash validation/peers/generate_peer_values.sh    # sets up target/peers-venv, then runs this script
    target/peers-venv/bin/python validation/peers/generate_peer_values.py [--check]

What it does:
  1. Checks that the pinned peer versions are installed (PINS below); stops otherwise.
  2. Recomputes the 29 original cases from their recorded inputs (LEGACY_INPUTS below: the script
     that drew them, "seed 7", was never committed and is lost, so their inputs are recorded here
     verbatim, bit for bit, as read from the file) with the named peer library.
  3. Draws the added Rayleigh-Rice cases (in-lobe; absorbing substrates) with
     numpy.random.default_rng(NEW_SEED) and computes them with pySCATMECH.
  4. Checks the SCATMECH conventions it relies on (complex-index sign, full-precision parameter
     passing) against Mitsuba and against closed forms.
  5. Compares every recomputed case with the one stored in the existing file (if any) and prints
     the max relative difference per kind; stops (exit 1, nothing written) if one exceeds its
     tolerance.
  6. Writes the file (json.dumps(indent=1) + newline), unless --check.
Re-running it gives the same bytes. Nothing in `cargo test` runs this script.
"""

import argparse
import cmath
import importlib.metadata as md
import json
import math
import os
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")

# The workspace root: this file is validation/peers/generate_peer_values.py.
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
OUT = os.path.join(ROOT, "tests", "data", "peer_values.json")
SCRIPT = "validation/peers/generate_peer_values.py"

PINS = {
    "numpy": "2.4.6",
    "py-pol": "1.3.0",
    "mitsuba": "3.9.1",
    "drjit": "1.5.0",
    "pySCATMECH": "0.1.10",
}
MITSUBA_VARIANT = "scalar_spectral_polarized"  # the PyPI wheels' CPU polarized variant (float32)
LEGACY_SEED = 7  # the lost original generator's seed, recorded in the file as "seed"
NEW_SEED = 20220807  # numpy.random.default_rng seed for the cases added by this script

# Inputs of the original 29 cases, copied bit for bit (Python float repr) from
# tests/data/peer_values.json as committed in 1df9c8e, in file order. Only inputs: every output is
# recomputed below. (Long lines: data.)
LEGACY_INPUTS = [
    ("jones_to_mueller", {"jones_re": [[0.0012301533574825742, 0.2987455375084699], [-0.2741378553622176, -0.8905918387572742]], "jones_im": [[-0.45467078517172255, -0.9916465549964624], [0.060143602597438485, 1.3402152455545335]]}),
    ("jones_to_mueller", {"jones_re": [[-0.49220651855132963, -0.6204748998199404], [0.4898420501851982, 0.35688700816006075]], "jones_im": [[0.10541424899789856, -0.9304680447082047], [-0.02925182246327349, 0.6953031944582878]]}),
    ("jones_to_mueller", {"jones_re": [[-1.344214547285082, -0.45761576104021817], [-1.901222739800844, -1.289537739784976]], "jones_im": [[-1.8417350377917323, -0.23509113107468127], [-1.2674464814437032, 0.2712643588217015]]}),
    ("jones_to_mueller", {"jones_re": [[0.15675108662422516, -0.18693094462995438], [-2.516759710820513, -0.5386928958466366]], "jones_im": [[-0.048500945401071985, 0.11330898600330756], [-1.5301357655053935, -0.47775327603393064]]}),
    ("jones_to_mueller", {"jones_re": [[-0.9785190780566395, -0.8088372394255993], [1.0608986233860787, -0.8075346753318965]], "jones_im": [[-0.0325217049455206, 0.8843898673831739], [-0.583600432743302, -0.11170194958415963]]}),
    ("jones_to_mueller", {"jones_re": [[0.11046414324948059, 0.06378177425506196], [-1.2250558264176934, 0.0761402303770081]], "jones_im": [[1.3588234217415376, -1.5471446781284823], [0.8593826880215982, 0.11935402569658124]]}),
    ("linear_polarizer", {"theta": 2.3331941156139333}),
    ("linear_retarder", {"theta": 2.3331941156139333, "delta": 2.269889027609814}),
    ("rotator", {"theta": 2.3331941156139333}),
    ("linear_polarizer", {"theta": 0.616908688475494}),
    ("linear_retarder", {"theta": 0.616908688475494, "delta": 0.3722890486115281}),
    ("rotator", {"theta": 0.616908688475494}),
    ("linear_polarizer", {"theta": -0.7060302162553027}),
    ("linear_retarder", {"theta": -0.7060302162553027, "delta": 2.0296972244945413}),
    ("rotator", {"theta": -0.7060302162553027}),
    ("linear_polarizer", {"theta": -2.1978599227519755}),
    ("linear_retarder", {"theta": -2.1978599227519755, "delta": 5.12920357960686}),
    ("rotator", {"theta": -2.1978599227519755}),
    ("fresnel_reflection", {"theta_i": 0.5691692573254687, "eta_re": 2.9383688647925426, "eta_im": 2.9499584650530513}),
    ("fresnel_reflection", {"theta_i": 0.907584380744777, "eta_re": 1.9501900842861635, "eta_im": 3.3822512190639413}),
    ("fresnel_reflection", {"theta_i": 0.22618202875255305, "eta_re": 1.3769090548457439, "eta_im": 1.1978198091476167}),
    ("fresnel_reflection", {"theta_i": 0.6037474471559725, "eta_re": 0.3804418724020623, "eta_im": 4.839140255244107}),
    ("fresnel_reflection", {"theta_i": 0.32250605603382004, "eta_re": 2.0481189715727264, "eta_im": 1.5021004073953514}),
    ("rayleigh_rice_gaussian", {"lambda_um": 0.911853918304653, "n": 2.06087915983999, "sigma_um": 0.003500700500357809, "length_um": 4.256356740197854, "theta_i": 1.2284326224884734, "theta_s": 1.1750918246547049, "phi_s": 0.438058325458492}),
    ("rayleigh_rice_gaussian", {"lambda_um": 0.4018219676326488, "n": 1.4502025434588321, "sigma_um": 0.018630208010145963, "length_um": 2.851167140802866, "theta_i": 0.23471824798358512, "theta_s": 1.149273962455411, "phi_s": 0.8895212581662504}),
    ("rayleigh_rice_gaussian", {"lambda_um": 0.6987859921316655, "n": 1.689174186968896, "sigma_um": 0.008808150360985468, "length_um": 1.3495482208728553, "theta_i": 0.04947447269861082, "theta_s": 1.1390844505420523, "phi_s": -0.20275702757954228}),
    ("rayleigh_rice_gaussian", {"lambda_um": 0.6833446394496147, "n": 1.6188123027142927, "sigma_um": 0.01527517347724363, "length_um": 0.3209449798484497, "theta_i": 0.48384085433476515, "theta_s": 0.03945538269934512, "phi_s": -2.3694388026468665}),
    ("rayleigh_rice_gaussian", {"lambda_um": 0.9770037647781573, "n": 2.055088949050069, "sigma_um": 0.009136184681400143, "length_um": 2.7139525179703057, "theta_i": 1.1346519711342067, "theta_s": 0.44747386709483405, "phi_s": 0.5673149732935472}),
    ("rayleigh_rice_gaussian", {"lambda_um": 0.7785790613376805, "n": 1.6620379101305658, "sigma_um": 0.010862871243423812, "length_um": 3.8731874397369084, "theta_i": 1.1819331081877154, "theta_s": 0.19638096149986015, "phi_s": 2.72325435759274}),
]

# --------------------------------------------------------------------------------- metadata strings
# Per kind: the `source`, `convention` and tolerance fields, exactly as in the original file.
META = {
    "jones_to_mueller": {
        "source": "pySCATMECH JonesMueller == py-pol Mueller.from_Jones",
        "convention": "same Stokes convention as gmueller (S3 = 2 Im<Ex* Ey>); compare directly",
    },
    "linear_polarizer": {
        "source": "Mitsuba 3.9.1 rotated_element(theta, linear_polarizer(1))",
        "tol": 2e-06,
        "convention": "identical in gmueller (no S3 coupling)",
    },
    "linear_retarder": {
        "source": "Mitsuba 3.9.1 rotated_element(theta, linear_retarder(delta)); fast axis at theta",
        "tol": 2e-06,
        "convention": "Mitsuba uses e^{+iwt}: gmueller value = D M D with D = diag(1,1,1,-1)",
    },
    "rotator": {
        "source": "Mitsuba 3.9.1 rotator(theta): rotates the reference frame",
        "tol": 2e-06,
        "convention": "frame rotation by +theta; equals gmueller T(-theta)",
    },
    "fresnel_reflection": {
        "source": "Mitsuba 3.9.1 specular_reflection(cos theta_i, eta); x axis = s",
        "tol": 3e-06,
        "convention": "Mitsuba uses e^{+iwt} (eta = n - i k internally): gmueller value with eta = "
                      "n + i kappa is D M D, D = diag(1,1,1,-1); Stokes x axis = s",
    },
    "rayleigh_rice_gaussian": {
        "source": "pySCATMECH 0.1.10 Microroughness_BRDF_Model (Germer 1997), Gaussian_PSD_Function",
        "convention": "PSD S(f) = pi sigma^2 l^2 exp(-(pi l f)^2), f in cycles/um, C(r) = sigma^2 "
                      "exp(-r^2/l^2); specular at theta_s = theta_i, phi_s = 0; Mueller in "
                      "SCATMECH's s/p frame ('psps'), same S3 sign as gmueller",
        "tol_rel": 1e-09,
    },
}
# The added Rayleigh-Rice cases carry a complex substrate index n + i kappa.
RR_NEW_CONVENTION = (
    META["rayleigh_rice_gaussian"]["convention"]
    + "; substrate index n + i kappa (kappa >= 0 absorbing, e^{-iwt}, as in gmueller), passed to "
    "SCATMECH as the optical constant (n,kappa): gmueller eta = n + i kappa, no conversion"
)
RR_NEW_SOURCE = META["rayleigh_rice_gaussian"]["source"] + f"; {SCRIPT}"

# Reproduction tolerance (relative to the case's scale) for the check against the stored file.
CHECK_TOL = {
    "jones_to_mueller": 1e-14,
    "linear_polarizer": 1e-6,
    "linear_retarder": 1e-6,
    "rotator": 1e-6,
    "fresnel_reflection": 1e-6,
    "rayleigh_rice_gaussian": 1e-12,
}


# ----------------------------------------------------------------------------------- peer imports
def check_versions():
    bad = []
    for pkg, want in PINS.items():
        try:
            have = md.version(pkg)
        except md.PackageNotFoundError:
            have = "not installed"
        if have != want:
            bad.append(f"{pkg} {have} (need {want})")
    if bad:
        sys.exit("version mismatch: " + ", ".join(bad) + " -- run bash validation/peers/generate_peer_values.sh")


check_versions()

import numpy as np  # noqa: E402
import drjit  # noqa: E402,F401
import mitsuba as mi  # noqa: E402
from py_pol.jones_matrix import Jones_matrix  # noqa: E402
from py_pol.mueller import Mueller  # noqa: E402
from pySCATMECH.brdf import BRDF_Model  # noqa: E402
from pySCATMECH.fresnel import FilmStack, OpticalFunction  # noqa: E402
from pySCATMECH.mueller import JonesMueller  # noqa: E402

if MITSUBA_VARIANT not in mi.variants():
    sys.exit(f"Mitsuba has no {MITSUBA_VARIANT} variant (have {mi.variants()})")
mi.set_variant(MITSUBA_VARIANT)

D = np.diag([1.0, 1.0, 1.0, -1.0])


def rows(m):
    """A 4x4 array as nested lists of Python floats."""
    return [[float(x) for x in r] for r in np.asarray(m, dtype=float).reshape(4, 4)]


def mitsuba_matrix(m):
    """A Mitsuba scalar Mueller matrix (spectral: 4 equal wavelengths) as a 4x4 float64 array."""
    out = np.zeros((4, 4))
    for i in range(4):
        for j in range(4):
            v = m[i, j]
            vals = [float(x) for x in v] if hasattr(v, "__len__") else [float(v)]
            if any(x != vals[0] for x in vals):
                raise RuntimeError(f"Mitsuba entry [{i},{j}] differs across wavelengths: {vals}")
            out[i, j] = vals[0]
    return out


# ------------------------------------------------------------------------------- per-kind compute
def jones_to_mueller(inp):
    j = np.array(inp["jones_re"]) + 1j * np.array(inp["jones_im"])
    m = np.array(JonesMueller(j), dtype=float).reshape(4, 4)
    # py-pol's numpy route must agree to rounding.
    pp = np.asarray(Mueller().from_Jones(Jones_matrix().from_matrix(j)).M, dtype=float)
    pp = pp.reshape(4, 4)
    dev = np.abs(pp - m).max() / np.abs(m).max()
    if dev > 1e-14:
        raise RuntimeError(f"py-pol and pySCATMECH disagree: {dev:.3g}")
    return {"mueller": rows(m)}, {"py-pol vs pySCATMECH": dev}


def linear_polarizer(inp):
    m = mi.mueller.rotated_element(inp["theta"], mi.mueller.linear_polarizer(1.0))
    return {"mueller": rows(mitsuba_matrix(m))}, {}


def linear_retarder(inp):
    m = mi.mueller.rotated_element(inp["theta"], mi.mueller.linear_retarder(inp["delta"]))
    return {"mueller": rows(mitsuba_matrix(m))}, {}


def rotator(inp):
    return {"mueller": rows(mitsuba_matrix(mi.mueller.rotator(inp["theta"])))}, {}


def mitsuba_fresnel(cos_i, eta):
    return mitsuba_matrix(mi.mueller.specular_reflection(cos_i, mi.Complex2f(eta.real, eta.imag)))


def fresnel_reflection(inp):
    m = mitsuba_fresnel(math.cos(inp["theta_i"]), complex(inp["eta_re"], inp["eta_im"]))
    return {"mueller": rows(m)}, {}


def substrate_param(n, kappa):
    """pySCATMECH's `substrate` value. A Python complex would be formatted with "%16g" (6
    significant digits) by pySCATMECH.model; a float goes through str() (all digits); an
    OpticalFunction of a complex goes through nkstr() = "(n,k)" with all digits."""
    if kappa == 0.0:
        return float(n)
    return OpticalFunction(complex(n, kappa))


def scatmech_rr(lam, n, kappa, sigma, length, ti, ts, ps):
    model = BRDF_Model(
        "Microroughness_BRDF_Model",
        wavelength=lam,
        substrate=substrate_param(n, kappa),
        type=0,
        psd={None: "Gaussian_PSD_Function", "sigma": sigma, "length": length},
    )
    p = model.getParameters()
    if p.get("psd") != "Gaussian_PSD_Function" or p.get("type") not in ("0", "0.0"):
        raise RuntimeError(f"unexpected SCATMECH parameters {p}")
    return np.array(model.MuellerBRDF(ti, ts, ps), dtype=float).reshape(4, 4)


def rayleigh_rice_gaussian(inp):
    m = scatmech_rr(inp["lambda_um"], inp["n"], inp.get("kappa", 0.0), inp["sigma_um"],
                    inp["length_um"], inp["theta_i"], inp["theta_s"], inp["phi_s"])
    return {"brdf_unpolarized": float(m[0, 0]), "mueller_brdf": rows(m)}, {}


COMPUTE = {
    "jones_to_mueller": jones_to_mueller,
    "linear_polarizer": linear_polarizer,
    "linear_retarder": linear_retarder,
    "rotator": rotator,
    "fresnel_reflection": fresnel_reflection,
    "rayleigh_rice_gaussian": rayleigh_rice_gaussian,
}
# Output field order per kind (inputs, outputs, metadata), as in the original file.
ORDER = {
    "jones_to_mueller": ["jones_re", "jones_im", "mueller", "source", "convention"],
    "linear_polarizer": ["theta", "mueller", "source", "tol", "convention"],
    "linear_retarder": ["theta", "delta", "mueller", "source", "tol", "convention"],
    "rotator": ["theta", "mueller", "source", "tol", "convention"],
    "fresnel_reflection": ["theta_i", "eta_re", "eta_im", "mueller", "source", "tol",
                           "convention"],
    "rayleigh_rice_gaussian": ["lambda_um", "n", "sigma_um", "length_um", "theta_i", "theta_s",
                               "phi_s", "brdf_unpolarized", "mueller_brdf", "source",
                               "convention", "tol_rel"],
}
RR_NEW_ORDER = ["lambda_um", "n", "kappa", "sigma_um", "length_um", "theta_i", "theta_s",
                "phi_s", "brdf_unpolarized", "mueller_brdf", "material", "lobe",
                "lobe_exponent", "source", "convention", "tol_rel"]


def build(kind, inp, meta, order):
    out, _ = COMPUTE[kind](inp)
    fields = {**inp, **out, **meta}
    missing = [k for k in order if k not in fields]
    if missing or set(fields) - set(order):
        raise RuntimeError(f"{kind}: field mismatch {missing} / {set(fields) - set(order)}")
    return {"kind": kind, **{k: fields[k] for k in order}}


# ------------------------------------------------------------------------- new Rayleigh-Rice cases
def sig(x, digits=12):
    """Rounds a drawn parameter to `digits` significant digits, so that every path into SCATMECH
    (str(), "%.16g", "(n,k)") passes it exactly and the JSON stays readable."""
    return float(f"{x:.{digits}g}")


def bragg(lam, ti, ts, ps):
    return ((math.sin(ts) * math.cos(ps) - math.sin(ti)) / lam, math.sin(ts) * math.sin(ps) / lam)


# (label, lobe, n, kappa, lambda_um or None to draw, theta_i range in degrees, l range in um)
# lobe "in": u = pi l |f| drawn in [0.2, 2] (PSD factor exp(-u^2) in [0.018, 0.96]);
# lobe "off": u in [2.5, 3.5] (PSD factor 5e-6 ... 2e-3).
# Short correlation lengths give wide lobes (in-lobe directions far from specular, large phi_s).
# Index values: gold, aluminium, silicon and chromium near 0.6 um (rounded literature values), an
# absorbing dielectric 1.6 + 0.05i (e.g. a dyed polymer) at a drawn wavelength.
SHORT, LONG = (0.1, 0.4), (0.4, 3.0)
NEW_SPECS = [
    ("dielectric", "in", None, 0.0, None, (60, 85), SHORT),
    ("dielectric", "in", None, 0.0, None, (60, 85), LONG),
    ("dielectric", "in", None, 0.0, None, (0, 30), SHORT),
    ("dielectric", "in", None, 0.0, None, (30, 60), SHORT),
    ("dielectric", "in", None, 0.0, None, (0, 85), LONG),
    ("dielectric", "in", None, 0.0, None, (0, 85), SHORT),
    ("dielectric", "in", None, 0.0, None, (0, 85), LONG),
    ("dielectric", "in", None, 0.0, None, (65, 80), SHORT),
    ("gold (approx.)", "in", 0.18, 3.4, 0.6, (0, 85), SHORT),
    ("gold (approx.)", "off", 0.18, 3.4, 0.6, (60, 80), LONG),
    ("aluminium (approx.)", "in", 1.2, 7.0, 0.6, (60, 80), LONG),
    ("aluminium (approx.)", "off", 1.2, 7.0, 0.6, (0, 60), SHORT),
    ("silicon (approx.)", "in", 3.9, 0.02, 0.6, (0, 85), SHORT),
    ("silicon (approx.)", "off", 3.9, 0.02, 0.6, (0, 85), LONG),
    ("absorbing dielectric", "in", 1.6, 0.05, None, (0, 85), LONG),
    ("absorbing dielectric", "off", 1.6, 0.05, None, (0, 85), SHORT),
    ("chromium (approx.)", "in", 3.1, 3.3, 0.6, (30, 75), SHORT),
    ("chromium (approx.)", "off", 3.1, 3.3, 0.6, (30, 75), LONG),
]
MAX_THETA_S = math.radians(85.0)


def new_rr_inputs():
    rng = np.random.default_rng(NEW_SEED)
    cases = []
    for label, lobe, n, kappa, lam, (ti_lo, ti_hi), (l_lo, l_hi) in NEW_SPECS:
        lam = sig(rng.uniform(0.4, 1.0)) if lam is None else lam
        n = sig(rng.uniform(1.3, 2.5)) if n is None else n
        sigma = sig(rng.uniform(0.002, 0.02))
        u_lo, u_hi = (0.2, 2.0) if lobe == "in" else (2.5, 3.5)
        for _ in range(100000):  # rejection: theta_s <= 85 deg, out of the plane of incidence
            length = sig(math.exp(rng.uniform(math.log(l_lo), math.log(l_hi))))
            ti = sig(math.radians(rng.uniform(ti_lo, ti_hi)))
            u = rng.uniform(u_lo, u_hi)
            psi = rng.uniform(-math.pi, math.pi)
            fx, fy = u * math.cos(psi) / (math.pi * length), u * math.sin(psi) / (math.pi * length)
            sx, sy = math.sin(ti) + lam * fx, lam * fy
            rho = math.hypot(sx, sy)
            if rho < math.sin(MAX_THETA_S) and abs(sy) > 0.02:
                break
        else:
            raise RuntimeError(f"no admissible direction for {label} {lobe}")
        ts, ps = sig(math.asin(rho)), sig(math.atan2(sy, sx))
        fx, fy = bragg(lam, ti, ts, ps)
        cases.append({
            "lambda_um": lam, "n": n, "kappa": kappa, "sigma_um": sigma, "length_um": length,
            "theta_i": ti, "theta_s": ts, "phi_s": ps, "material": label, "lobe": lobe,
            "lobe_exponent": sig((math.pi * length) ** 2 * (fx * fx + fy * fy), 6),
        })
    return cases


# ------------------------------------------------------------------------- convention self-checks
def fresnel_closed_form(cos_i, eta):
    """r_s, r_p for e^{-iwt}, eta = n + i kappa (kappa >= 0 absorbing), principal square root:
    the transmitted wave exp(i (k_x x - k0 q z)) (substrate z < 0) decays since Im q >= 0."""
    sin2 = 1.0 - cos_i * cos_i
    e = eta * eta
    q = cmath.sqrt(e - sin2)
    return (cos_i - q) / (cos_i + q), (e * cos_i - q) / (e * cos_i + q)


def convention_checks(new_inputs):
    """SCATMECH's index convention, checked three ways; returns printable lines."""
    lines = []
    # (1) Full precision through the `substrate` parameter: the string "(n,0)" (as OpticalFunction
    #     passes it) gives bit-identical results to the float path used by the original cases.
    c = LEGACY_INPUTS[-1][1]
    a = scatmech_rr(c["lambda_um"], c["n"], 0.0, c["sigma_um"], c["length_um"], c["theta_i"],
                    c["theta_s"], c["phi_s"])
    model = BRDF_Model("Microroughness_BRDF_Model", wavelength=c["lambda_um"],
                       substrate=OpticalFunction(complex(c["n"], 0.0)), type=0,
                       psd={None: "Gaussian_PSD_Function", "sigma": c["sigma_um"],
                            "length": c["length_um"]})
    b = np.array(model.MuellerBRDF(c["theta_i"], c["theta_s"], c["phi_s"]), dtype=float)
    if not np.array_equal(a, b.reshape(4, 4)):
        raise RuntimeError("substrate '(n,0)' and float n give different SCATMECH results")
    lines.append("substrate passed as '(n,k)' string: bit-identical to the float path (k = 0)")
    # (2) SCATMECH's specular Fresnel coefficients (empty film stack, substrate (n,k)) equal the
    #     e^{-iwt}, n + i kappa closed form; and (3) their Mueller matrix equals D M_mitsuba D,
    #     the relation between Mitsuba and gmueller established by the fresnel_reflection cases.
    worst_cf, worst_mi = 0.0, 0.0
    etas = sorted({(c["n"], c["kappa"]) for c in new_inputs if c["kappa"] > 0})
    for n, k in etas:
        eta = complex(n, k)
        for deg in (0.0, 30.0, 60.0, 80.0):
            th = math.radians(deg)
            r = FilmStack().reflectionCoefficient(th, 0.6, OpticalFunction(1.0),
                                                  OpticalFunction(eta))
            rs, rp = complex(r[0][0]), complex(r[1][1])
            cs, cp = fresnel_closed_form(math.cos(th), eta)
            worst_cf = max(worst_cf, abs(rs - cs), abs(rp - cp))
            # Jones matrix in the (s, p) basis, x = s as in Mitsuba's specular_reflection.
            m_sc = np.array(JonesMueller(np.array([[rs, 0], [0, rp]])), dtype=float).reshape(4, 4)
            m_mi = D @ mitsuba_fresnel(math.cos(th), eta) @ D
            worst_mi = max(worst_mi, np.abs(m_sc - m_mi).max())
    if worst_cf > 1e-13:
        raise RuntimeError(f"SCATMECH Fresnel != e^(-iwt) n+ik closed form: {worst_cf:.3g}")
    if worst_mi > 3e-6:
        raise RuntimeError(f"SCATMECH Fresnel Mueller != D M_mitsuba D: {worst_mi:.3g}")
    lines.append(f"SCATMECH r_s, r_p for substrate (n,k), k > 0 = e^(-iwt) n+ik closed form "
                 f"(max |diff| {worst_cf:.2g}); Mueller = D M_Mitsuba(eta = n+ik) D "
                 f"(max |diff| {worst_mi:.2g}, float32 Mitsuba)")
    return lines


# ------------------------------------------------------------------------------------------ main
def rel_diff(kind, new, old):
    """Max |new - old| over the case's outputs, relative to the case's scale (max |M|; for
    Rayleigh-Rice M00, as the Rust test compares)."""
    if kind == "rayleigh_rice_gaussian":
        a, b = np.array(new["mueller_brdf"]), np.array(old["mueller_brdf"])
        scale = abs(old["mueller_brdf"][0][0])
        d = max(np.abs(a - b).max(), abs(new["brdf_unpolarized"] - old["brdf_unpolarized"]))
        return d / scale
    a, b = np.array(new["mueller"]), np.array(old["mueller"])
    return np.abs(a - b).max() / np.abs(b).max()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="compare only, do not write")
    args = ap.parse_args()

    versions = ", ".join(f"{p} {v}" for p, v in PINS.items())
    cases = []
    for kind, inp in LEGACY_INPUTS:
        cases.append(build(kind, inp, META[kind], ORDER[kind]))
    n_legacy = len(cases)
    new_inputs = new_rr_inputs()
    rr_meta = {"source": RR_NEW_SOURCE, "convention": RR_NEW_CONVENTION,
               "tol_rel": META["rayleigh_rice_gaussian"]["tol_rel"]}
    for inp in new_inputs:
        cases.append(build("rayleigh_rice_gaussian", inp, rr_meta, RR_NEW_ORDER))
    doc = {
        "generator": f"{SCRIPT} ({versions}; Mitsuba variant {MITSUBA_VARIANT})",
        "seed": LEGACY_SEED,
        "seed_new_cases": NEW_SEED,
        "note": f"cases 1-{n_legacy}: inputs drawn by the original generator (seed {LEGACY_SEED}, "
                f"script lost), recorded in {SCRIPT} and recomputed by it; cases "
                f"{n_legacy + 1}-{len(cases)}: rayleigh_rice_gaussian cases drawn by {SCRIPT} "
                f"with numpy.random.default_rng({NEW_SEED}); missing kappa means 0",
        "cases": cases,
    }

    print("== versions:", versions, "| Mitsuba variant", MITSUBA_VARIANT)
    print("== convention checks")
    for line in convention_checks(new_inputs):
        print("  ", line)

    failed = False
    print(f"== reproduction of the stored cases ({os.path.relpath(OUT, ROOT)})")
    if os.path.exists(OUT):
        with open(OUT) as fh:
            old_text = fh.read()
        old_cases = json.loads(old_text)["cases"]
        per_kind = {}
        for i, new in enumerate(cases):
            if i >= len(old_cases):
                break
            old = old_cases[i]
            same_inputs = old["kind"] == new["kind"] and all(
                old.get(k) == new[k] for k in new
                if k not in ("mueller", "mueller_brdf", "brdf_unpolarized"))
            group = "original" if i < n_legacy else "added"
            key = (group, new["kind"])
            if not same_inputs:
                per_kind.setdefault(key, []).append(None)
                continue
            per_kind.setdefault(key, []).append(rel_diff(new["kind"], new, old))
        for (group, kind), ds in per_kind.items():
            mismatched = sum(d is None for d in ds)
            ds = [d for d in ds if d is not None]
            worst = max(ds) if ds else float("nan")
            ok = worst <= CHECK_TOL[kind] if ds else True
            if group == "original" and (mismatched or not ok):
                failed = True
            exact = sum(d == 0.0 for d in ds)
            print(f"   {group:8s} {kind:24s} {len(ds):2d} compared, {exact:2d} bit-identical, "
                  f"max rel diff {worst:.3g} (limit {CHECK_TOL[kind]:g})"
                  + (f"; {mismatched} with other inputs (replaced)" if mismatched else ""))
        print(f"   stored file has {len(old_cases)} cases; generated {len(cases)} "
              f"({n_legacy} original + {len(new_inputs)} added)")
    else:
        old_text = None
        print("   no stored file")
    if failed:
        sys.exit("the stored original cases are NOT reproduced: nothing written")

    print("== added rayleigh_rice_gaussian cases")
    for c in cases[n_legacy:]:
        print(f"   {c['material']:22s} {c['lobe']:3s} lam={c['lambda_um']:.3f} "
              f"n={c['n']:.4g}+{c['kappa']:.3g}i ti={math.degrees(c['theta_i']):5.1f} "
              f"ts={math.degrees(c['theta_s']):5.1f} ps={math.degrees(c['phi_s']):7.1f} "
              f"(pi l f)^2={c['lobe_exponent']:.3g} M00={c['brdf_unpolarized']:.3e}")

    text = json.dumps(doc, indent=1) + "\n"
    if text == old_text:
        print("== output identical to the stored file (byte for byte)")
    elif args.check:
        print("== output differs from the stored file (--check: not written)")
        sys.exit(1)
    if not args.check and text != old_text:
        with open(OUT, "w") as fh:
            fh.write(text)
        print(f"== wrote {os.path.relpath(OUT, ROOT)} ({len(cases)} cases)")


if __name__ == "__main__":
    main()
