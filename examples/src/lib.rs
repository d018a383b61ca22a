//! navguard's paper reproductions, kept out of the library: the simulated
//! Jackal UGV of Baek & Jo 2018 ([`ugv`], run by `navguard-baek`), and the
//! binaries `navguard-tight` and `navguard-gan` (Shen et al. 2022) in
//! `src/bin/`. The examples and probes next to `Cargo.toml` run the library
//! over simulated and real flights (see each file's doc comment).

pub mod ugv;
