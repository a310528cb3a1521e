//! Where the method breaks, one test binary: inputs at the edges of every
//! accepted range bake and render finite or are refused by name
//! (`extremes`, and through the command line and the writer, `cli`), and
//! the two approximations with a known failure mode fail exactly as
//! derived: the density estimate at extreme gather radii (`gather`) and
//! fixed-step ray marching in an optically thick medium (`integration`);
//! a sequence's stage of any length is streamed (`stage`).

#[path = "../common/mod.rs"]
mod common;

mod chunks;
mod cli;
mod extremes;
mod gather;
mod integration;
mod stage;
