//! The stack (vectorization) operator and the Kronecker product (Lemma S1.1).
