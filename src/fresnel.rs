//! Fresnel amplitude coefficients of a planar interface, as Jones matrices in an explicit s/p basis.
