"""pySCATMECH peer: Rayleigh-Rice (first-order vector perturbation) Mueller-matrix BRDF.

Model: SCATMECH's Microroughness_BRDF_Model with a Gaussian_PSD_Function (sigma = 0.01 um,
correlation length 0.5 um), wavelength 0.5 um, substrate n = 1.5 (glass), reflection.
Geometry: incidence 45 deg; 1024 precomputed viewing directions (theta_s uniform in [0, 80] deg,
phi_s uniform in [-180, 180] deg), cycled through.

Timed, per Python call (one geometry each):
  * BRDF_Model.MuellerBRDF(thetai, thetas, phis)  - the documented pySCATMECH API (returns a
    pySCATMECH MuellerMatrix);
  * SCATPY.BRDF(handle, thetai, thetas, phis, 0, "psps") - the compiled extension function that
    MuellerBRDF wraps (returns a nested list), i.e. the same C++ work with less Python around it.
pySCATMECH has no batch call: SCATPY's BRDF, BRDFJones, VectoredBRDF and VectoredBRDFJones all
take one geometry. Run by validation/peers/run.sh.
"""

import math
import sys

import numpy as np

from _timing import bench, row, skip

PEER = "pySCATMECH"
OP = "Rayleigh-Rice Mueller BRDF (Microroughness_BRDF_Model, Gaussian PSD)"

try:
    import SCATPY
    from pySCATMECH.brdf import BRDF_Model
except Exception as e:  # noqa: BLE001 - report any import failure as a skip
    skip(PEER, OP, f"import failed: {e!r}")
    sys.exit(0)

model = BRDF_Model(
    "Microroughness_BRDF_Model",
    wavelength=0.5,
    substrate=complex(1.5, 0.0),
    type=0,
    psd={None: "Gaussian_PSD_Function", "sigma": 0.01, "length": 0.5},
)
params = model.getParameters()
if (params.get("psd"), params.get("psd.sigma"), params.get("psd.length"), params.get("lambda")) != (
        "Gaussian_PSD_Function", "0.01", "0.5", "0.5"):
    skip(PEER, OP, f"could not select the Gaussian PSD, parameters: {params}")
    sys.exit(0)

rng = np.random.default_rng(7)
N_GEOM = 1024
thetai = math.radians(45.0)
geoms = [(thetai, math.radians(ts), math.radians(ps))
         for ts, ps in zip(rng.uniform(0, 80, N_GEOM), rng.uniform(-180, 180, N_GEOM))]

# Sanity: a finite, non-negative M00 everywhere.
for ti, ts, ps in geoms[:16]:
    m = np.asarray(model.MuellerBRDF(ti, ts, ps), dtype=float).reshape(4, 4)
    if not (np.all(np.isfinite(m)) and m[0, 0] >= 0.0):
        skip(PEER, OP, f"non-finite or negative M00 at {ti, ts, ps}: {m}")
        sys.exit(0)

handle = model.handle


def sweep_wrapper():
    for ti, ts, ps in geoms:
        model.MuellerBRDF(ti, ts, ps)


def sweep_raw():
    for ti, ts, ps in geoms:
        SCATPY.BRDF(handle, ti, ts, ps, 0.0, "psps")


med, lo = bench(sweep_wrapper, N_GEOM, warmup=1, samples=11, max_total_s=6.0)
row(PEER, OP + " via BRDF_Model.MuellerBRDF", "f64", 1, med, lo,
    "per Python call; no batch call exists")
med, lo = bench(sweep_raw, N_GEOM, warmup=1, samples=11, max_total_s=6.0)
row(PEER, OP + " via SCATPY.BRDF (extension function)", "f64", 1, med, lo,
    "per Python call; no batch call exists")
