//! Our VDB files, one test binary: writer to reader round trips and
//! corrupt input (`roundtrip`), one verdict on every damaged file from both
//! of the renderer's readers (`verdicts`), and the reference readers and
//! writer: OpenVDB 10 (`openvdb`), Blender and usd-core (`blender`).

#[path = "../common/mod.rs"]
mod common;

mod blender;
mod openvdb;
mod roundtrip;
mod verdicts;
