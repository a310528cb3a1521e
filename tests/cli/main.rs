//! The `aurora` command line, driven as a user and a farm drive it: each
//! module runs the binary and checks the files it writes, the exit status
//! and the message against what the commands promise.
//!
//! - `end_to_end`: a small scene baked, read back and rendered; bytes
//!   independent of the thread count; bad input refused;
//! - `frames`, `resume`, `plan`: sequences, shards, reruns and their
//!   estimate;
//! - `inputs`, `outputs`: inputs and outputs that are not regular files,
//!   killed and concurrent bakes; `foreign_files`: a bake's names held by
//!   files it did not write;
//! - `preview`, `watch`: `aurora preview` and its watch under real editors'
//!   saves;
//! - `profile`, `bench`: `aurora profile`'s CSV and `aurora bench --quick`;
//! - `keogram`: `aurora keogram` of a baked sequence, a drifting arc tracked;
//! - `schema`: the committed schema and the documents generated from it;
//! - `quick_start`: the README's quick start, installed and run as written.
//! - `overrides`, `messages`: `--set` and render's flags over a scene, and
//!   the scene's errors in plain words.
//! - `data`: the tables read from the data folder, and the default that
//!   reads none.
//! - `globe`: scenes anywhere on the globe, the field's dip refused or
//!   warned about.
//! - `sky`: `aurora sky`'s airglow and stars map, and its refusals.
//! - `oval`: `[oval]`'s arcs placed over a site, and its refusals.
//! - `limits`: the process's limits (memory, file size) and inputs that
//!   say more than they show (`--set` over two lines, shard variables at
//!   the ends of a 64-bit integer).
//! - `recolour`: a bake re-coloured at render time for another observer
//!   from its line grids, and refused without them.

#[path = "../common/mod.rs"]
mod common;

mod bench;
mod data;
mod dome;
mod end_to_end;
mod foreign_files;
mod frames;
mod globe;
mod inputs;
mod keogram;
mod limits;
mod messages;
mod observer;
mod outputs;
mod oval;
mod overrides;
mod plan;
mod preview;
mod profile;
mod quick_start;
mod recolour;
mod resume;
mod schema;
mod sky;
mod streams;
mod watch;
