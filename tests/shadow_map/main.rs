//! Shadow maps: one map per face (`maps`), cascades, warps and fits
//! (`partitions`), and bias and edges (`bias`), in one test binary.

mod bias;
#[path = "../common/mod.rs"]
mod common;
mod maps;
mod partitions;
