#!/usr/bin/env python3
"""Generates tests/data/rough_interface_peer.json: first-order (Rayleigh-Rice / Elson) scattering
by a rough interface for all four SCATMECH scattering types (reflection and transmission, from
either side), and Mitsuba 3's smooth-interface Fresnel transmission. Reference data only, each
value in its library's own convention; the conventions are recorded in the file (see
tests/data/README.md, "rough_interface_peer.json").

    bash validation/peers/generate_peer_values.sh --rough-interface           # venv, then this script
    bash validation/peers/generate_peer_values.sh --rough-interface --check   # exit 1 if the file would change
    target/peers-venv/bin/python validation/peers/generate_rough_interface_values.py [--check]

What it does:
  1. Checks the pinned peer versions (PINS); stops otherwise.
  2. Builds a fixed case list (build_inputs: THETA_I_DEG, GRID, NEAR_LOBE_EXPONENTS, ...; the
     random directions and near-lobe azimuths come from numpy.random.default_rng(SEED)) and
     evaluates SCATMECH's Microroughness_BRDF_Model with a Gaussian_PSD_Function for types 0-3:
     the Mueller matrix (BRDF_Model.MuellerBRDF) and the Jones matrix (BRDF_Model.JonesBRDF),
     default coordinates "psps"; records SCATMECH's k, s, p vectors of both beams.
  3. Evaluates Mitsuba's mi.mueller.specular_transmission (and specular_reflection for the
     energy check) in the scalar_spectral_polarized variant.
  4. Sanity checks (exit 1, nothing written, if one fails; results stored under "checks"):
     (a) type 0 = Germer's closed form, and the real-index rayleigh_rice_gaussian cases of
     peer_values.json reproduced; (b) Mueller = A (J* x J) A^-1 of the Jones matrix; (c) M00 > 0;
     (d) reciprocity between the types (0<->0, 1<->3, 2<->2) with the recorded s/p vectors;
     (e) SCATMECH's "plane" Jones matrix from the recorded s/p vectors; right-handed (s, p, k);
     SCATMECH still refusing absorbing substrates for types 1-3; Mitsuba = its closed form and
     R + T = 1.
  5. Writes the file (json.dumps(indent=1) + newline) unless --check. Re-running gives the same
     bytes. Nothing in `cargo test` runs this script.
"""

import argparse
import importlib.metadata as md
import json
import math
import os
import platform
import sys

os.environ.setdefault("OMP_NUM_THREADS", "1")

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
OUT = os.path.join(ROOT, "tests", "data", "rough_interface_peer.json")
PEER_VALUES = os.path.join(ROOT, "tests", "data", "peer_values.json")
SCRIPT = "validation/peers/generate_rough_interface_values.py"

PINS = {
    "numpy": "2.4.6",
    "mitsuba": "3.9.1",
    "drjit": "1.5.0",
    "pySCATMECH": "0.1.10",
}
PYTHON_PIN = "3.11"  # major.minor checked; the full version is recorded
MITSUBA_VARIANT = "scalar_spectral_polarized"
SEED = 20261202  # numpy.random.default_rng seed for the drawn directions


def check_versions():
    bad = []
    for pkg, want in PINS.items():
        try:
            have = md.version(pkg)
        except md.PackageNotFoundError:
            have = "not installed"
        if have != want:
            bad.append(f"{pkg} {have} (need {want})")
    if not platform.python_version().startswith(PYTHON_PIN + "."):
        bad.append(f"python {platform.python_version()} (need {PYTHON_PIN}.x)")
    if bad:
        sys.exit("version mismatch: " + ", ".join(bad)
                 + " -- run bash validation/peers/generate_peer_values.sh --rough-interface")


check_versions()

import numpy as np  # noqa: E402
import drjit  # noqa: E402,F401
import mitsuba as mi  # noqa: E402
from pySCATMECH.brdf import BRDF_Model  # noqa: E402

if MITSUBA_VARIANT not in mi.variants():
    sys.exit(f"Mitsuba has no {MITSUBA_VARIANT} variant (have {mi.variants()})")
mi.set_variant(MITSUBA_VARIANT)

# ------------------------------------------------------------------------------------ parameters
LAMBDA_UM = 0.5  # vacuum wavelength (SCATMECH parameter `lambda`)
SIGMA_UM = 0.01
PSDS = [  # (label, sigma, length): S(f) = pi sigma^2 l^2 exp(-(pi l f)^2)
    ("wide", SIGMA_UM, 0.5),
    ("narrow", SIGMA_UM, 3.0),
]
INDICES = [1.5, 2.4]  # real substrate index (SCATMECH rejects k != 0 for types 1-3)
TYPE_NAMES = {0: "DOWNUP", 1: "DOWNDOWN", 2: "UPDOWN", 3: "UPUP"}
THETA_I_DEG = {0: [0.0, 20.0, 45.0, 70.0], 1: [0.0, 20.0, 45.0, 70.0],
               2: [0.0, 20.0, 35.0, 45.0, 70.0], 3: [0.0, 20.0, 35.0, 45.0, 70.0]}
# Grid directions (exit polar angle in the exit medium, azimuth), used with the wide PSD; each
# (type, n, theta_i) takes the next two of this list in turn, so every pair is used.
GRID_THETA_S_DEG = [5.0, 30.0, 60.0, 80.0]
GRID_PHI_S_DEG = [0.0, 30.0, 90.0, 150.0, 180.0]
GRID = [(ts, ps) for ts in GRID_THETA_S_DEG for ps in GRID_PHI_S_DEG]
GRID_PER_COMBO = 2
NEAR_LOBE_EXPONENTS = [0.3, 1.5, 5.0]  # (pi l |f|)^2 of the near-lobe directions (narrow PSD)
GRAZING_THETA_S_DEG = [60.0, 80.0, 89.0]  # type 3 beyond the critical angle (no Snell exit)
MAX_SIN_EXIT = math.sin(math.radians(87.0))  # drawn / near-lobe exits kept below 87 deg


def media(t, n):
    """(incident, exit) refractive index of SCATMECH type t."""
    return {0: (1.0, 1.0), 1: (1.0, n), 2: (n, n), 3: (n, 1.0)}[t]


# ---------------------------------------------------------------------- SCATMECH geometry (brdf.cpp)
def unit(v):
    return v / np.linalg.norm(v)


def perpto(a, b):
    """SCATMECH vector3d.cpp perpto(a, b): unit(unit(a) x unit(b)) (fallbacks not needed here)."""
    c = np.cross(unit(a), unit(b))
    nc = np.linalg.norm(c)
    if nc <= 1e-10:
        raise RuntimeError("perpto of parallel vectors")
    return c / nc


def k_vectors(t, ti, ts, ps):
    """SCATMECH brdf.cpp BRDF_Model::convert: incident and exit propagation directions."""
    ki = (np.array([math.sin(ti), 0.0, -math.cos(ti)]) if t in (0, 1)
          else np.array([math.sin(ti), 0.0, math.cos(ti)]))
    ko_xy = [math.sin(ts) * math.cos(ps), math.sin(ts) * math.sin(ps)]
    ko = (np.array(ko_xy + [math.cos(ts)]) if t in (0, 3) else np.array(ko_xy + [-math.cos(ts)]))
    return ki, ko


def basis_sp(k):
    """SCATMECH jmatrix.cpp GetBasisVectorsSP: s = perpto(z, k), p = perpto(k, s); s = y if
    |k_x|, |k_y| <= 1e-10."""
    if abs(k[0]) > 1e-10 or abs(k[1]) > 1e-10:
        s = perpto(np.array([0.0, 0.0, 1.0]), k)
    else:
        s = np.array([0.0, 1.0, 0.0])
    return s, perpto(k, s)


def bragg(t, n, lam, ti, ts, ps):
    """SCATMECH rough.cpp Roughness_BRDF_Model::Bragg_Frequency at rotation 0 (vacuum lambda):
    f = (n_o sin ts cos ps - n_i sin ti, n_o sin ts sin ps) / lambda."""
    ni, no = media(t, n)
    return ((no * math.sin(ts) * math.cos(ps) - ni * math.sin(ti)) / lam,
            no * math.sin(ts) * math.sin(ps) / lam)


# ------------------------------------------------------------------------- Jones -> Mueller (S1.7)
A_MUL = np.array([[1, 0, 0, 1], [1, 0, 0, -1], [0, 1, 1, 0], [0, -1j, 1j, 0]])
A_MUL_INV = np.linalg.inv(A_MUL)


def mueller_of_jones(j):
    """gmueller's S1.7: M = A (J* (x) J) A^-1, column stacking, S3 = 2 Im(Ex* Ey) convention."""
    m = A_MUL @ np.kron(np.conj(j), j) @ A_MUL_INV
    if np.abs(m.imag).max() > 1e-12 * np.abs(m).max():
        raise RuntimeError("complex Mueller matrix")
    return m.real


def rows(m):
    return [[float(x) for x in r] for r in np.asarray(m, dtype=float)]


def vec(v):
    return [float(x) for x in v]


# ------------------------------------------------------------------------------- SCATMECH models
_MODELS = {}


def model(t, n, sigma, length, lam=LAMBDA_UM, substrate=None):
    key = (t, n, sigma, length, lam, substrate)
    if key not in _MODELS:
        m = BRDF_Model("Microroughness_BRDF_Model", wavelength=lam,
                       substrate=float(n) if substrate is None else substrate, type=t,
                       psd={None: "Gaussian_PSD_Function", "sigma": sigma, "length": length})
        p = m.getParameters()
        # getParameters prints 6 significant digits; the values themselves reach SCATMECH
        # exactly (float -> str(), PSD parameters "%.16g"; see tests/data/README.md).
        if (p.get("psd") != "Gaussian_PSD_Function" or int(float(p["type"])) != t
                or not math.isclose(float(p["lambda"]), lam, rel_tol=1e-5)
                or not math.isclose(float(p["psd.sigma"]), sigma, rel_tol=1e-5)
                or not math.isclose(float(p["psd.length"]), length, rel_tol=1e-5)):
            raise RuntimeError(f"unexpected SCATMECH parameters {p}")
        _MODELS[key] = m
    return _MODELS[key]


def scatmech(t, n, sigma, length, ti, ts, ps, coords="psps"):
    mdl = model(t, n, sigma, length)
    mm = np.array(mdl.MuellerBRDF(ti, ts, ps, 0.0, coords), dtype=float).reshape(4, 4)
    jj = np.array(mdl.JonesBRDF(ti, ts, ps, 0.0, coords), dtype=complex).reshape(2, 2)
    return mm, jj


# ---------------------------------------------------------------------------- recorded conventions
# Read from the pySCATMECH 0.1.10 sdist (scatmech/*.cpp, *.h; SCATPYmodule.cpp; pySCATMECH/*.py) and
# from Mitsuba 3.9.1's installed headers (mitsuba/include/mitsuba/render/{mueller,fresnel}.h); see
# tests/data/README.md. "checked" = also confirmed numerically by this script.
CONVENTIONS = {
    "sources_read": "pySCATMECH 0.1.10 sdist pyscatmech-0.1.10.tar.gz (sha256 7606835d60886fc6"
        "2bda790d8f5168040b2bdfd6f612fe149f3522cf76db980e); Mitsuba 3.9.1 wheel headers "
        "mitsuba/include/mitsuba/render/{mueller,fresnel}.h",
    "scatmech_types": "type 0 DOWNUP: incident from the ambient (vacuum, index 1) above, "
        "reflected back up; 1 DOWNDOWN: from the ambient, transmitted into the substrate; 2 "
        "UPDOWN: from inside the substrate (below), reflected back down; 3 UPUP: from inside the "
        "substrate, transmitted out into the ambient (brdf.h enum; brdf.h is_forward/is_backward)",
    "angles": "theta_i: polar angle of the incident beam in the incident medium; theta_s: polar "
        "angle of the exit beam in the exit medium; phi_s: exit azimuth, 0 = forward (the Snell "
        "/ specular direction is n_i sin theta_i = n_o sin theta_s, phi_s = 0); all from the "
        "local normal of the respective side, 0 <= theta < 90 deg (brdf.cpp "
        "BRDF_Model::set_geometry returns a zero matrix for |theta| >= 90 deg)",
    "k_vectors": "fixed frame, substrate below z = 0, normal +z: k_i = (sin ti, 0, -cos ti) for "
        "types 0,1 and (sin ti, 0, +cos ti) for types 2,3; k_o = (sin ts cos ps, sin ts sin ps, "
        "+cos ts) for types 0,3 and (..., -cos ts) for types 1,2 (brdf.cpp "
        "BRDF_Model::convert, both overloads). Recorded per case as k_i, k_o (propagation "
        "directions, unit)",
    "sp_basis": "s = perpto(z, k) = unit(z x k), p = perpto(k, s) = unit(k x s); if |k_x| and "
        "|k_y| <= 1e-10 then s = y (jmatrix.cpp GetBasisVectorsSP; perpto in vector3d.cpp = "
        "unit(unit(a) x unit(b))). So (s, p, k) is right-handed for both beams. Recorded per "
        "case as s_i, p_i, s_o, p_o; checked: SCATMECH's own 'plane' Jones matrix is the psps "
        "one rotated with these vectors (GetBasisVectorsParPerp, GetJonesRotator)",
    "coords": "default 'psps' (pySCATMECH brdf.py BRDF_Model.MuellerBRDF/JonesBRDF coords='psps'; "
        "SCATPYmodule.cpp BRDF/BRDFJones default \"psps\"; brdf.h model_cs = psps, not changed "
        "by Microroughness_BRDF_Model): input Stokes/Jones basis (s_i, p_i), output (s_o, p_o), "
        "x = s, y = p",
    "jones": "jones_re/jones_im [row][col] = pySCATMECH JonesBRDF()[row][col] = "
        "[[ss, ps], [sp, pp]] (SCATPYmodule.cpp PyJones: ((SS, PS), (SP, PP))), where ps = "
        "p->s, sp = s->p (mueller.h class JonesMatrix: storage {pp, ss, ps, sp}; operator*("
        "JonesVector): out_s = ss in_s + ps in_p, out_p = sp in_s + pp in_p, JonesVector = "
        "(s, p)). So it is the ordinary matrix E_out = J E_in in the (s, p) = (x, y) bases",
    "mueller": "mueller_brdf = pySCATMECH MuellerBRDF (1/sr) = MuellerMatrix(JonesMatrix) "
        "(mueller.cpp, Bohren & Huffman) = A (J* (x) J) A^-1 of the recorded Jones matrix with "
        "gmueller's A (S3 = 2 Im(E_x* E_y)) -- checked (b) for every case; same Stokes "
        "convention as gmueller (x = s). |J|^2 = BRDF / BTDF: power per solid angle in the exit "
        "medium per incident power per cos theta_s",
    "time_convention": "e^{-iwt} (tests/data/README.md: SCATMECH's (n,k) optical constants, "
        "principal square roots with Im >= 0 = waves decaying away from the interface). With a "
        "real index every Jones matrix here is real except where a normal wave-vector component "
        "sqrt(eps - sin^2) is imaginary, i.e. a wave evanescent in the ambient (flag "
        "evanescent_ambient_wave: type 1 with n sin ts > 1, type 2 with n sin ti > 1 or n sin "
        "ts > 1, type 3 with n sin ti > 1)",
    "evanescent_branch": "types 2 and 3 take that root with Im > 0 (decaying, the e^{-iwt} "
        "choice, as type 0 for absorbing substrates); type 1 (exit angle beyond the critical "
        "angle, n sin ts > 1) takes Im < 0 (flag scatmech_sqrt_branch_im_negative). Found "
        "numerically, by evaluating urough.cpp's expressions on both branches in a throwaway "
        "diagnostic (not committed; urough.cpp forms the root as sqrt(1. - k*k) with a complex "
        "k, so the sign of a zero imaginary part decides); consequence, checked (d): type 1 and type 3 are "
        "reciprocal to 1e-14 for M00 and for all 16 entries where no wave is evanescent, but "
        "for the evanescent pairs only after conjugating one side (Mueller D M D, D = "
        "diag(1,1,1,-1)). Inferred, not proven: the type-1 values in those cases are the "
        "complex conjugate of the e^{-iwt} result, i.e. gmueller's Mueller matrix there would "
        "be D M D of the stored one; magnitudes (and M00, M01, M10, M11) are unaffected",
    "normal_exit": "at theta_s = 0 SCATMECH's psps matrix is the limit along azimuth phi_s "
        "(it depends on phi_s), while GetBasisVectorsSP returns s = y: the two agree only for "
        "phi_s = 0, so every theta_s = 0 case here has phi_s = 0 (checked by the script). "
        "theta_i = 0 has no such issue (incidence is always at azimuth 0; s_i = y is its limit)",
    "wavelength_scaling": "lambda_um is the vacuum wavelength (parameter lambda). urough.cpp "
        "Microroughness_BRDF_Model::jones: for types 2,3 (is_backward) eps -> 1/eps and the "
        "prefactor wavelength _lambda = lambda / n (wavelength in the substrate, the incident "
        "medium): reflection prefactor sqrt(16 pi^2 / _lambda^4 cos ti cos ts S(f)), "
        "transmission 4 pi (1 - eps) sqrt(eps) sqrt(q1 q0 S(f)) / _lambda^2; and for types 2,3 "
        "the off-diagonal Jones elements (ps, sp) are negated. The Bragg frequency uses the "
        "vacuum lambda (rough.cpp Roughness_BRDF_Model::Bragg_Frequency): f = (n_o sin ts cos "
        "ps - n_i sin ti, n_o sin ts sin ps) / lambda, in cycles/um, recorded as bragg_f_per_um",
    "psd": "Gaussian_PSD_Function (rough.cpp): S(f) = A exp(-(B f)^2), A = pi sigma^2 l^2, "
        "B = pi l, f = |f| in cycles/um (isotropic: PSD_Function::psd(fx, fy) = psd(|f|), "
        "rough.h); lobe_exponent = (pi l |f|)^2",
    "transmission_model": "types 1,3: Elson, JOSA A 12, 729 (1995), single interface (comment "
        "in urough.cpp); types 0,2: Germer, Appl. Opt. 36, 8798 (1997)",
    "substrate": "real n passed as a float (str(), all digits); SCATMECH refuses an absorbing "
        "substrate (k != 0) for types 1,2,3 (brdf.cpp BRDF_Model::setup: 'Absorbing substrate "
        "for type==1, 2, or 3') -- checked, see checks.absorbing_substrate_by_type",
    "mitsuba": "mi.mueller.specular_transmission(cos_theta_i, eta) (mueller.h, real eta only): "
        "M = F [[(ts^2+tp^2)/2, (ts^2-tp^2)/2, 0, 0], [same, swapped], [0, 0, ts tp, 0], "
        "[0, 0, 0, ts tp]] with ts = 1 + Re a_s, tp = (1 + Re a_p) eta_ti (fresnel.h "
        "fresnel_polarized, real overload), F = -eta_it cos_theta_t_signed / cos_theta_i = "
        "eta_it |cos t| / |cos i| (0 if |cos i| <= 1e-8): the POWER transmittance (M00 = 1 - "
        "R, checked); the radiance factor eta_ti^2 is NOT included (the dielectric plugin "
        "applies it separately in Radiance mode). Under TIR cos_theta_t_signed = 0, so M = 0 "
        "(entries -0.0). cos_theta_i < 0 means incidence from the eta side: eta_it = 1/eta. "
        "eta = n_transmitted / n_incident for cos_theta_i > 0. Float32; inputs recorded as the "
        "float32 values passed (eta_f32, cos_theta_i_f32). Frames: Stokes x axis = s = unit(n x "
        "k) for both beams (src/bsdfs/dielectric.cpp sample(): s_axis_in = cross(n, -wo_hat), "
        "s_axis_out = cross(n, wi_hat); read in a Mitsuba 3 repository snapshot not pinned to "
        "3.9.1, the wheel ships no plugin sources), y = k x x (mueller.h rotate_stokes_basis: angle sign from forward . "
        "(current x target)). e^{+iwt}: gmueller value = D M D, D = diag(1,1,1,-1), which "
        "leaves this block-diagonal matrix unchanged",
}


# ------------------------------------------------------------------------------------ case list
def exit_direction(t, n, ti, fx, fy):
    """Exit (theta_s, phi_s) of Bragg frequency (fx, fy), or None if evanescent / too grazing."""
    ni, no = media(t, n)
    ux = ni * math.sin(ti) + LAMBDA_UM * fx
    uy = LAMBDA_UM * fy
    rho = math.hypot(ux, uy) / no
    if rho >= MAX_SIN_EXIT:
        return None
    return math.asin(rho), math.atan2(uy, ux)


def build_inputs():
    rng = np.random.default_rng(SEED)
    cases = []
    grid_idx = 0
    for t in range(4):
        for n in INDICES:
            ni, no = media(t, n)
            for ti_deg in THETA_I_DEG[t]:
                ti = math.radians(ti_deg)
                base = {"type": t, "n": n, "theta_i": ti}
                beyond = ni * math.sin(ti) > 1.0  # only for types 2, 3 (incident in substrate)
                sin_snell = ni * math.sin(ti) / no
                snell = math.asin(sin_snell) if sin_snell <= 1.0 else None
                # wide PSD: grid, one random direction, the specular / Snell direction
                wide, narrow = PSDS
                for _ in range(GRID_PER_COMBO):
                    ts_deg, ps_deg = GRID[grid_idx % len(GRID)]
                    grid_idx += 1
                    cases.append({**base, "psd": wide, "theta_s": math.radians(ts_deg),
                                  "phi_s": math.radians(ps_deg), "group": "grid"})
                ts_r = float(rng.uniform(0.0, math.radians(85.0)))
                ps_r = float(rng.uniform(-math.pi, math.pi))
                cases.append({**base, "psd": wide, "theta_s": ts_r, "phi_s": ps_r,
                              "group": "random"})
                if snell is not None:
                    cases.append({**base, "psd": wide, "theta_s": snell, "phi_s": 0.0,
                                  "group": "specular"})
                # narrow PSD: specular / Snell direction and near-lobe directions, or (type 3
                # beyond the critical angle) grazing exits in the plane of incidence
                if snell is not None:
                    cases.append({**base, "psd": narrow, "theta_s": snell, "phi_s": 0.0,
                                  "group": "specular"})
                    for e in NEAR_LOBE_EXPONENTS:
                        fmag = math.sqrt(e) / (math.pi * narrow[2])
                        for _ in range(1000):
                            psi = float(rng.uniform(-math.pi, math.pi))
                            d = exit_direction(t, n, ti, fmag * math.cos(psi),
                                               fmag * math.sin(psi))
                            if d is not None:
                                break
                        else:
                            raise RuntimeError("no near-lobe exit direction")
                        cases.append({**base, "psd": narrow, "theta_s": d[0], "phi_s": d[1],
                                      "group": "near_lobe"})
                else:
                    # the exit closest to the (evanescent) Snell direction is grazing; the narrow
                    # lobe is reached only for n sin ti near 1, so the wide PSD is used as well
                    for psd, ts_list in ((wide, GRAZING_THETA_S_DEG),
                                         (narrow, GRAZING_THETA_S_DEG[-1:])):
                        for ts_deg in ts_list:
                            cases.append({**base, "psd": psd, "theta_s": math.radians(ts_deg),
                                          "phi_s": 0.0, "group": "grazing_beyond_critical"})
                for c in cases:
                    c.setdefault("beyond_critical", bool(beyond))
    # SCATMECH's psps matrix at theta_s = 0 is the limit along phi_s, its s/p vectors there are
    # fixed (s = y): consistent only for phi_s = 0 (CONVENTIONS["normal_exit"]).
    if any(c["theta_s"] == 0.0 and c["phi_s"] != 0.0 for c in cases):
        raise RuntimeError("a case with theta_s = 0 and phi_s != 0")
    return cases


# --------------------------------------------------------------------------------- case compute
def compute_case(c):
    t, n, ti, ts, ps = c["type"], c["n"], c["theta_i"], c["theta_s"], c["phi_s"]
    label, sigma, length = c["psd"]
    ni, no = media(t, n)
    mm, jj = scatmech(t, n, sigma, length, ti, ts, ps)
    ki, ko = k_vectors(t, ti, ts, ps)
    si, pi_ = basis_sp(ki)
    so, po = basis_sp(ko)
    fx, fy = bragg(t, n, LAMBDA_UM, ti, ts, ps)
    # A wave in the ambient whose normal component is imaginary: the ambient partner of a
    # substrate-side beam beyond the critical angle (type 1: the exit, n sin ts > 1; type 2: the
    # incident or the exit beam; type 3: the incident beam, n sin ti > 1).
    ev_i = t in (2, 3) and n * math.sin(ti) > 1.0
    ev_o = t in (1, 2) and n * math.sin(ts) > 1.0
    evanescent = bool(ev_i or ev_o)
    out = {
        "type": t,
        "type_name": TYPE_NAMES[t],
        "group": c["group"],
        "n": n,
        "n_incident": ni,
        "n_exit": no,
        "lambda_um": LAMBDA_UM,
        "psd": label,
        "sigma_um": sigma,
        "length_um": length,
        "theta_i": ti,
        "theta_s": ts,
        "phi_s": ps,
        "beyond_critical": c["beyond_critical"],
        "evanescent_ambient_wave": evanescent,
        "scatmech_sqrt_branch_im_negative": t == 1 and evanescent,
        "bragg_f_per_um": [fx, fy],
        "lobe_exponent": (math.pi * length) ** 2 * (fx * fx + fy * fy),
        "k_i": vec(ki),
        "k_o": vec(ko),
        "s_i": vec(si),
        "p_i": vec(pi_),
        "s_o": vec(so),
        "p_o": vec(po),
        "mueller_brdf": rows(mm),
        "jones_re": [[float(x.real) for x in r] for r in jj],
        "jones_im": [[float(x.imag) for x in r] for r in jj],
    }
    return out, mm, jj


# -------------------------------------------------------------------------------------- checks
def germer_type0(n, lam, sigma, length, ti, ts, ps):
    """Rayleigh-Rice type 0 from the paper (Germer, Appl. Opt. 36, 8798 (1997), as
    tests/common/oracle.rs rayleigh_rice_factors), real or complex substrate permittivity eps:
    J = sqrt(16 pi^2 / lambda^4 cos ti cos ts S(f)) [[ss, ps], [sp, pp]] in (s, p)."""
    eps = complex(n) ** 2
    si_, so_ = math.sin(ti), math.sin(ts)
    ci, co = math.cos(ti), math.cos(ts)
    qi, qs = np.sqrt(eps - si_ * si_), np.sqrt(eps - so_ * so_)
    em1 = eps - 1.0
    ss = em1 * math.cos(ps) / ((ci + qi) * (co + qs))
    pp = em1 * (eps * si_ * so_ - qs * qi * math.cos(ps)) / ((eps * ci + qi) * (eps * co + qs))
    ps_ = -em1 * qi * math.sin(ps) / ((eps * ci + qi) * (co + qs))
    sp = -em1 * qs * math.sin(ps) / ((ci + qi) * (eps * co + qs))
    f2 = ((so_ * math.cos(ps) - si_) ** 2 + (so_ * math.sin(ps)) ** 2) / lam ** 2
    psd = math.pi * sigma ** 2 * length ** 2 * math.exp(-(math.pi * length) ** 2 * f2)
    amp = math.sqrt(16 * math.pi ** 2 / lam ** 4 * ci * co * psd)
    return amp * np.array([[ss, ps_], [sp, pp]])


def reversed_geometry(t, ti, ts, ps):
    """The reciprocal path (incident along -k_o, exit along -k_i) in SCATMECH's geometry: type,
    angles, and the rotation about z that maps SCATMECH's reversed frame back onto the forward
    one (the reversed incident azimuth phi_s + pi is SCATMECH's azimuth 0)."""
    t_rev = {0: 0, 1: 3, 2: 2, 3: 1}[t]
    # A normal exit (forward ti = 0) is passed with phi_s = 0: at theta_s = 0 SCATMECH's psps
    # Jones matrix is the limit along azimuth phi_s while GetBasisVectorsSP gives s = y, and the
    # two agree only for phi_s = 0 (see CONVENTIONS["normal_exit"]).
    return t_rev, ts, ti, (-ps if ti != 0.0 else 0.0), ps + math.pi


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def reciprocity(c, jj):
    """Reciprocity: the amplitude for (incident u along k_i -> exit v along k_o) equals, up to a
    scalar, the amplitude for (incident v along -k_o -> exit u along -k_i). Returns (relative
    deviation of the Mueller matrices after scaling, the same with the reversed Jones matrix
    complex-conjugated, M00 ratio forward / reversed)."""
    t, n, ti, ts, ps = c["type"], c["n"], c["theta_i"], c["theta_s"], c["phi_s"]
    t_r, ti_r, ts_r, ps_r, alpha = reversed_geometry(t, ti, ts, ps)
    _, jr = scatmech(t_r, n, c["sigma_um"], c["length_um"], ti_r, ts_r, ps_r)
    kir, kor = k_vectors(t_r, ti_r, ts_r, ps_r)
    r = rot_z(alpha)
    e_in = [r @ v for v in basis_sp(kir)]   # reversed incident basis, forward frame
    e_out = [r @ v for v in basis_sp(kor)]  # reversed exit basis, forward frame
    ko = np.array(c["k_o"])
    ki = np.array(c["k_i"])
    if np.abs(r @ kir + ko).max() > 1e-12 or np.abs(r @ kor + ki).max() > 1e-12:
        raise RuntimeError("reversed geometry does not reverse the path")
    v = [np.array(c["s_o"]), np.array(c["p_o"])]
    u = [np.array(c["s_i"]), np.array(c["p_i"])]
    t_in = np.array([[e_in[a] @ v[b] for b in range(2)] for a in range(2)])
    t_out = np.array([[e_out[a] @ u[b] for b in range(2)] for a in range(2)])
    j_back = (t_out.T @ jr @ t_in).T  # the reversed amplitudes in the forward (u, v) bases
    mf, mb = mueller_of_jones(jj), mueller_of_jones(j_back)
    ratio = mf[0, 0] / mb[0, 0]
    d = np.diag([1.0, 1.0, 1.0, -1.0])  # complex conjugation of the Jones matrix
    return (np.abs(mf - ratio * mb).max() / mf[0, 0],
            np.abs(mf - ratio * (d @ mb @ d)).max() / mf[0, 0], ratio)


def check_plane(c, jj):
    """SCATMECH's own "plane" Jones matrix equals the psps one rotated with the s/p vectors
    written here (GetJonesRotator, GetBasisVectorsParPerp in jmatrix.cpp; brdf.cpp convert):
    confirms the recorded s/p vectors are SCATMECH's. None where k_i || k_o."""
    ki, ko = np.array(c["k_i"]), np.array(c["k_o"])
    if np.linalg.norm(np.cross(ki, ko)) < 1e-6:
        return None
    _, jp = scatmech(c["type"], c["n"], c["sigma_um"], c["length_um"], c["theta_i"],
                     c["theta_s"], c["phi_s"], "plane")
    perp = perpto(ki, ko)
    par_in, par_out = perpto(ki, perp), perpto(ko, perp)
    si, pi_, so, po = (np.array(c[k]) for k in ("s_i", "p_i", "s_o", "p_o"))
    # rotator from basis (x_i, y_i) to (x_o, y_o) as a (first, second) component matrix
    r_out = np.array([[perp @ so, perp @ po], [par_out @ so, par_out @ po]])
    r_in = np.array([[si @ perp, si @ par_in], [pi_ @ perp, pi_ @ par_in]])
    return np.abs(r_out @ jj @ r_in - jp).max() / np.abs(jp).max()


# -------------------------------------------------------------------------------------- Mitsuba
def mitsuba_matrix(m):
    out = np.zeros((4, 4))
    for i in range(4):
        for j in range(4):
            v = m[i, j]
            vals = [float(x) for x in v] if hasattr(v, "__len__") else [float(v)]
            if any(x != vals[0] for x in vals):
                raise RuntimeError(f"Mitsuba entry [{i},{j}] differs across wavelengths: {vals}")
            out[i, j] = vals[0]
    return out


def f32(x):
    return float(np.float32(x))


MI_ETAS = [("1.5", 1.5), ("2.4", 2.4), ("1/1.5", 1 / 1.5), ("1/2.4", 1 / 2.4)]
MI_COS = [1.0, 0.9999, 0.99, 0.9, 0.8, 0.7071067811865476, 0.5, 0.3, 0.1, 0.01, 0.001]
MI_COS_INSIDE = [-0.9, -0.5, -0.1]  # cos < 0: incident from the eta side (Mitsuba's convention)


def transmission_closed_form(cos_i, eta):
    """What mueller.h specular_transmission computes, in float64: power transmittance matrix
    (eta_it cos t / cos i) [[(ts^2+tp^2)/2, (ts^2-tp^2)/2, 0, 0], ..., [0, 0, 0, ts tp]] with
    ts = 2 cos i / (cos i + eta_it cos t), tp = 2 cos i / (eta_it cos i + cos t); 0 under TIR."""
    eta_it = eta if cos_i >= 0 else 1.0 / eta
    ci = abs(cos_i)
    sin2_t = (1.0 - ci * ci) / eta_it ** 2
    if sin2_t > 1.0:
        return np.zeros((4, 4)), True
    ct = math.sqrt(1.0 - sin2_t)
    ts = 2 * ci / (ci + eta_it * ct)
    tp = 2 * ci / (eta_it * ci + ct)
    fac = eta_it * ct / ci if ci > 1e-8 else 0.0
    a, b, cc = 0.5 * fac * (ts * ts + tp * tp), 0.5 * fac * (ts * ts - tp * tp), fac * ts * tp
    return np.array([[a, b, 0, 0], [b, a, 0, 0], [0, 0, cc, 0], [0, 0, 0, cc]]), False


def mitsuba_cases():
    """Returns the cases and the largest |Mitsuba - closed form| and |T00 + R00 - 1|, as
    {"general": ..., "near_critical": ...}: within 1e-3 of the critical cosine, cos theta_t is
    ~0.05 and Mitsuba's float32 arithmetic loses about 1/cos^2 theta_t more."""
    out = []
    worst_cf = {"general": 0.0, "near_critical": 0.0}
    worst_energy = {"general": 0.0, "near_critical": 0.0}
    inputs = [(lab, eta, c, False) for lab, eta in MI_ETAS for c in MI_COS]
    for lab, eta in MI_ETAS:
        if eta < 1.0:
            cc = math.sqrt(1.0 - eta * eta)  # cos of the critical angle
            inputs += [(lab, eta, cc + 1e-3, True), (lab, eta, cc - 1e-3, True)]
    inputs += [(lab, eta, c, False) for lab, eta in MI_ETAS[:2] for c in MI_COS_INSIDE]
    for lab, eta, cos_i, near in inputs:
        e32, c32 = f32(eta), f32(cos_i)
        m = mitsuba_matrix(mi.mueller.specular_transmission(c32, e32))
        r = mitsuba_matrix(mi.mueller.specular_reflection(c32, mi.Complex2f(e32, 0.0)))
        cf, tir = transmission_closed_form(c32, e32)
        group = "near_critical" if near else "general"
        worst_cf[group] = max(worst_cf[group], np.abs(m - cf).max())
        if not tir and abs(c32) > 1e-8:
            worst_energy[group] = max(worst_energy[group], abs(m[0, 0] + r[0, 0] - 1.0))
        out.append({
            "eta": lab,
            "eta_f32": e32,
            "cos_theta_i": cos_i,
            "cos_theta_i_f32": c32,
            "tir": tir,
            "near_critical": near,
            "mueller": rows(m),
            "closed_form_f64": rows(cf),
        })
    return out, worst_cf, worst_energy


# ------------------------------------------------------------------------------------------ main
def fail(msg):
    sys.exit(f"CHECK FAILED: {msg} -- nothing written")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--check", action="store_true", help="compare only, do not write")
    args = ap.parse_args()

    versions = {"pySCATMECH": md.version("pySCATMECH"), "mitsuba": md.version("mitsuba"),
                "drjit": md.version("drjit"), "numpy": md.version("numpy"),
                "python": platform.python_version()}
    print("== versions:", ", ".join(f"{k} {v}" for k, v in versions.items()),
          "| Mitsuba variant", MITSUBA_VARIANT)

    # ---- SCATMECH cases
    cases, mats = [], []
    for c in build_inputs():
        rec, mm, jj = compute_case(c)
        cases.append(rec)
        mats.append((mm, jj))

    print(f"== SCATMECH: {len(cases)} cases")
    # (c) M00 > 0
    bad = [i for i, (mm, _) in enumerate(mats) if not mm[0, 0] > 0.0]
    if bad:
        fail(f"M00 <= 0 in cases {bad}")
    # (b) Mueller = A (J* (x) J) A^-1 of the returned Jones matrix
    dev_b = max(np.abs(mueller_of_jones(jj) - mm).max() / mm[0, 0] for mm, jj in mats)
    if dev_b > 1e-12:
        fail(f"Mueller != A (J* x J) A^-1 of JonesBRDF: {dev_b:.3g}")
    print(f"   (b) MuellerBRDF = A (J* x J) A^-1 of JonesBRDF: max rel dev {dev_b:.2g}")
    # (a) type 0 against the closed form (all type-0 cases) and the stored peer_values.json
    dev_a = 0.0
    for c, (mm, _) in zip(cases, mats):
        if c["type"] == 0:
            mg = mueller_of_jones(germer_type0(c["n"], c["lambda_um"], c["sigma_um"],
                                               c["length_um"], c["theta_i"], c["theta_s"],
                                               c["phi_s"]))
            dev_a = max(dev_a, np.abs(mg - mm).max() / mm[0, 0])
    if dev_a > 1e-12:
        fail(f"type 0 != Germer closed form: {dev_a:.3g}")
    with open(PEER_VALUES) as fh:
        stored = [c for c in json.load(fh)["cases"] if c["kind"] == "rayleigh_rice_gaussian"
                  and c.get("kappa", 0.0) == 0.0]
    dev_a2 = 0.0
    for c in stored:
        mdl = model(0, c["n"], c["sigma_um"], c["length_um"], lam=c["lambda_um"])
        mm = np.array(mdl.MuellerBRDF(c["theta_i"], c["theta_s"], c["phi_s"]), dtype=float)
        ref = np.array(c["mueller_brdf"])
        dev_a2 = max(dev_a2, np.abs(mm.reshape(4, 4) - ref).max() / ref[0, 0])
        mg = mueller_of_jones(germer_type0(c["n"], c["lambda_um"], c["sigma_um"],
                                           c["length_um"], c["theta_i"], c["theta_s"],
                                           c["phi_s"]))
        dev_a = max(dev_a, np.abs(mg - ref).max() / ref[0, 0])
    if dev_a2 > 1e-12 or dev_a > 1e-12:
        fail(f"type 0 != stored peer_values.json cases: {dev_a2:.3g} / closed form {dev_a:.3g}")
    print(f"   (a) type 0 = Germer closed form (this file's type-0 cases and the "
          f"{len(stored)} real-index stored cases): max rel dev {dev_a:.2g}; stored "
          f"peer_values.json cases reproduced to {dev_a2:.2g}")
    # (d) reciprocity
    # Pairs with an evanescent ambient-side wave (type 1 with n sin ts > 1 <-> type 3 with
    # n sin ti > 1) are reciprocal only after conjugating one side: SCATMECH's type 1 takes
    # the other branch of that square root (CONVENTIONS["evanescent_branch"]).
    dev_d, dev_conj, ratio_dev, n_conj, n_conj_differs = 0.0, 0.0, 0.0, 0, 0
    for c, (mm, jj) in zip(cases, mats):
        d, dc, ratio = reciprocity(c, jj)
        expected = (c["n_exit"] / c["n_incident"]) ** 2
        ratio_dev = max(ratio_dev, abs(ratio / expected - 1.0))
        if c["evanescent_ambient_wave"] and c["type"] in (1, 3):
            n_conj += 1
            dev_conj = max(dev_conj, dc)
            n_conj_differs += int(d > 1e-6)
        else:
            dev_d = max(dev_d, d)
    if dev_d > 1e-10 or dev_conj > 1e-10 or ratio_dev > 1e-10:
        fail(f"reciprocity: Mueller {dev_d:.3g}, conjugated pairs {dev_conj:.3g}, M00 ratio vs "
             f"(n_o/n_i)^2 {ratio_dev:.3g}")
    print(f"   (d) reciprocity M(i->o) = (n_o/n_i)^2 M_reversed, full 4x4 via the recorded s/p "
          f"bases: max rel dev {dev_d:.2g}; M00 ratio {ratio_dev:.2g}; the {n_conj} type-1/3 "
          f"cases with an evanescent ambient wave: reciprocal with D M D to {dev_conj:.2g} "
          f"({n_conj_differs} of them differ without the conjugation)")
    # (e) "plane" coordinates reproduced from the recorded s/p vectors
    dev_e = [check_plane(c, jj) for c, (_, jj) in zip(cases, mats)]
    n_e = sum(d is not None for d in dev_e)
    dev_e = max(d for d in dev_e if d is not None)
    if dev_e > 1e-12:
        fail(f"'plane' Jones from the recorded s/p vectors: {dev_e:.3g}")
    print(f"   (e) SCATMECH 'plane' Jones = rotation of psps by the recorded s/p vectors "
          f"({n_e} cases): max rel dev {dev_e:.2g}")
    # (g) right-handed orthonormal (s, p, k)
    dev_g = 0.0
    for c in cases:
        for s, p, k in ((c["s_i"], c["p_i"], c["k_i"]), (c["s_o"], c["p_o"], c["k_o"])):
            s, p, k = np.array(s), np.array(p), np.array(k)
            dev_g = max(dev_g, np.abs(np.cross(s, p) - k).max(), abs(s @ k), abs(p @ k))
    if dev_g > 1e-15:
        fail(f"(s, p, k) not right-handed orthonormal: {dev_g:.3g}")
    # absorbing substrate: SCATMECH refuses types 1-3 (brdf.cpp BRDF_Model::setup)
    from pySCATMECH.fresnel import OpticalFunction
    absorbing = {}
    for t in range(4):
        try:
            mdl = BRDF_Model("Microroughness_BRDF_Model", wavelength=LAMBDA_UM,
                             substrate=OpticalFunction(complex(1.5, 0.01)), type=t,
                             psd={None: "Gaussian_PSD_Function", "sigma": SIGMA_UM,
                                  "length": 0.5})
            mdl.MuellerBRDF(0.3, 0.2, 0.1)
            absorbing[str(t)] = "evaluates"
        except Exception as e:  # noqa: BLE001
            absorbing[str(t)] = "error: " + str(e).strip().splitlines()[0][:120]
    print(f"   absorbing substrate (1.5+0.01i): {absorbing}")
    if absorbing["0"] != "evaluates" or any(absorbing[k] == "evaluates" for k in "123"):
        fail(f"absorbing-substrate behaviour changed: {absorbing}")

    # ---- Mitsuba
    mcases, dev_f, dev_energy = mitsuba_cases()
    if (dev_f["general"] > 1e-6 or dev_energy["general"] > 1e-6
            or dev_f["near_critical"] > 2e-5 or dev_energy["near_critical"] > 2e-5):
        fail(f"Mitsuba transmission vs closed form {dev_f}, R + T - 1 {dev_energy}")
    print(f"== Mitsuba: {len(mcases)} cases; max |M - closed form (f64)| "
          f"{dev_f['general']:.2g} ({dev_f['near_critical']:.2g} within 1e-3 of the critical "
          f"cosine); max |M00_T + M00_R - 1| {dev_energy['general']:.2g} "
          f"({dev_energy['near_critical']:.2g})")

    counts = {}
    for c in cases:
        key = f"type {c['type']}, n = {c['n']}"
        counts[key] = counts.get(key, 0) + 1
    for k, v in counts.items():
        print(f"   {k}: {v}")

    doc = {
        "generator": SCRIPT,
        "versions": versions,
        "mitsuba_variant": MITSUBA_VARIANT,
        "seed": SEED,
        "conventions": CONVENTIONS,
        "checks": {
            "a_type0_closed_form_max_rel": f"{dev_a:.1e}",
            "a_peer_values_reproduced_max_rel": f"{dev_a2:.1e}",
            "b_mueller_from_jones_max_rel": f"{dev_b:.1e}",
            "c_m00_positive": True,
            "d_reciprocity_max_rel": f"{dev_d:.1e}",
            "d_reciprocity_evanescent_pairs_after_conjugation_max_rel": f"{dev_conj:.1e}",
            "d_reciprocity_evanescent_pairs_count": n_conj,
            "d_reciprocity_evanescent_pairs_differing_without_conjugation": n_conj_differs,
            "e_plane_coords_from_recorded_sp_max_rel": f"{dev_e:.1e}",
            "absorbing_substrate_by_type": absorbing,
            "mitsuba_vs_closed_form_max_abs": {k: f"{v:.1e}" for k, v in dev_f.items()},
            "mitsuba_energy_R_plus_T_max_abs_dev": {k: f"{v:.1e}"
                                                    for k, v in dev_energy.items()},
        },
        "scatmech": {
            "model": "Microroughness_BRDF_Model",
            "psd_model": "Gaussian_PSD_Function",
            "psds": {lab: {"sigma_um": s, "length_um": l} for lab, s, l in PSDS},
            "lambda_um": LAMBDA_UM,
            "coords": "psps",
            "counts": counts,
            "cases": cases,
        },
        "mitsuba_specular_transmission": {
            "function": "mi.mueller.specular_transmission(cos_theta_i, eta)",
            "cases": mcases,
        },
    }
    text = json.dumps(doc, indent=1) + "\n"
    old = open(OUT).read() if os.path.exists(OUT) else None
    if text == old:
        print(f"== output identical to the stored {os.path.relpath(OUT, ROOT)} (byte for byte)")
    elif args.check:
        print("== output differs from the stored file (--check: not written)")
        sys.exit(1)
    else:
        with open(OUT, "w") as fh:
            fh.write(text)
        print(f"== wrote {os.path.relpath(OUT, ROOT)} ({len(cases)} SCATMECH + {len(mcases)} "
              f"Mitsuba cases)")


if __name__ == "__main__":
    main()
