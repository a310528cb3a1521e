//! The files a bake writes and reads: OpenVDB ([`vdb`]), the USD stage
//! ([`usd`]) and the bake folder that holds them with the report
//! ([`bake_folder`]).

pub mod bake_folder;
pub mod usd;
pub mod vdb;
