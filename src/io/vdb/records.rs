//! A VDB file's leaf records, read where they lie: the file's bytes
//! ([`FileBytes`], read into memory) and one grid's located
//! records as a [`LeafSource`] ([`FileLeaves`]), each decoded when a
//! consumer asks for it (the renderer's medium builder, through the adapter
//! above this layer). The records are located by a
//! [`super::parse::Decode::Locate`] parse, which validated them.

use super::parse::Tree;
use crate::grid::leaf_source::{LeafError, LeafSource, LeafValues, Scratch};
use crate::grid::{Transform, VoxelValue};
use glam::IVec3;
use std::path::Path;

/// One grid of a file as a [`LeafSource`]: its leaves located by a
/// [`super::parse::Decode::Locate`] parse, each record decoded when the medium's
/// builder asks for it, into the builder's per-thread scratch.
pub struct FileLeaves<'a, T> {
    /// The grid's name.
    pub name: String,
    pub transform: Transform,
    /// The grid's located leaves.
    pub tree: &'a Tree<T>,
    /// The whole file's bytes (the spans' offsets are into them).
    pub data: &'a [u8],
}

macro_rules! file_leaves {
    ($t:ty) => {
        impl LeafSource for FileLeaves<'_, $t> {
            fn name(&self) -> &str {
                &self.name
            }
            fn transform(&self) -> Transform {
                self.transform
            }
            fn channels(&self) -> usize {
                <$t as VoxelValue>::COMPONENTS
            }
            fn background(&self) -> [f32; 3] {
                self.tree.background.components()
            }
            fn leaf_count(&self) -> usize {
                self.tree.spans.len()
            }
            fn origin(&self, i: usize) -> IVec3 {
                self.tree.spans[i].origin
            }
            fn mask(&self, i: usize) -> &[u64; crate::grid::LEAF_MASK_WORDS] {
                &self.tree.spans[i].mask
            }
            fn half(&self) -> bool {
                self.tree.format.half
            }
            fn values_half<'s>(&'s self, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s, u16>, LeafError> {
                if !self.tree.format.half {
                    return Err(format!("grid `{}` does not store half floats", self.name).into());
                }
                let span = &self.tree.spans[i];
                let mut c = super::cursor::Cursor::new(self.data);
                c.seek(span.start as u64)?;
                let slots = super::decode::read_stored_half(
                    &mut c,
                    self.tree.format,
                    crate::grid::LEAF_NUM_VALUES,
                    &span.mask,
                    <$t as VoxelValue>::COMPONENTS,
                    &mut scratch.halves,
                    &mut scratch.bytes,
                )?;
                Ok(match slots {
                    super::decode::StoredSlots::All => LeafValues::All(&scratch.halves),
                    super::decode::StoredSlots::Active => LeafValues::Active(&scratch.halves),
                })
            }
            fn values<'s>(&'s self, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s>, LeafError> {
                let span = &self.tree.spans[i];
                let mut c = super::cursor::Cursor::new(self.data);
                c.seek(span.start as u64)?;
                let slots = super::decode::read_stored_f32(
                    &mut c,
                    self.tree.format,
                    crate::grid::LEAF_NUM_VALUES,
                    &span.mask,
                    <$t as VoxelValue>::COMPONENTS,
                    &mut scratch.values,
                    &mut scratch.bytes,
                )?;
                Ok(match slots {
                    super::decode::StoredSlots::All => LeafValues::All(&scratch.values),
                    super::decode::StoredSlots::Active => LeafValues::Active(&scratch.values),
                })
            }
        }
    };
}
file_leaves!(f32);
file_leaves!([f32; 3]);

/// A file's bytes, read into memory in full when the file is opened.
///
/// Not mapped: a mapped file that another process truncates or rewrites in
/// place (`cp` over it) while it is read raises SIGBUS at the first lost
/// page, which no error path can catch. Read, the file is ours from then
/// on: a later truncation or rewrite changes nothing, and one during the
/// read is found by the length check ([`FileBytes::open`]) and refused as
/// an I/O error. The cost is memory: the file's size, held while the
/// medium is built (its records are decoded from these bytes), and one
/// copy from the page cache (about 0.05 s for a 190 MB file); the medium's
/// budget (`crate::render::medium::build::MEDIUM_MEMORY_FRACTION`) leaves
/// the rest of the process's limit for it.
pub struct FileBytes(Vec<u8>);

impl FileBytes {
    /// The bytes of the regular file at `path`.
    pub fn open(path: &Path) -> std::io::Result<FileBytes> {
        // Only a regular file is read (`crate::util::input_file`).
        let file = crate::util::input_file::open(path)?;
        let len = file.metadata()?.len();
        crate::util::input_file::read_exactly(&file, len).map(FileBytes)
    }

    /// The file's bytes.
    pub fn bytes(&self) -> &[u8] {
        &self.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::scratch::folder;

    /// A file truncated (`ftruncate`) after it was opened keeps its bytes
    /// for the reader: no signal, the same bytes as before.
    #[test]
    fn a_file_truncated_after_it_was_opened_keeps_its_bytes() {
        let d = folder("records", "truncated");
        let p = d.join("a.vdb");
        let content: Vec<u8> = (0..300_000u32).map(|i| (i.wrapping_mul(2654435761u32) >> 24) as u8).collect();
        std::fs::write(&p, &content).unwrap();
        let bytes = FileBytes::open(&p).unwrap();
        std::fs::OpenOptions::new().write(true).open(&p).unwrap().set_len(0).unwrap();
        assert_eq!(std::fs::metadata(&p).unwrap().len(), 0);
        // Every page read after the truncation (a mapping would fault here).
        assert_eq!(bytes.bytes(), content.as_slice());
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// A file that is not the length it had when opened (truncated with
    /// `ftruncate` between the length check and the read, or grown) is an
    /// error, not a short or a long buffer; and the readers' error for it
    /// is an I/O failure (exit status 1), not the user's input.
    #[test]
    fn a_file_whose_length_changed_during_the_read_is_an_io_failure() {
        use crate::io::vdb::read::VdbReadError;
        use crate::util::input_file::read_exactly;
        let d = folder("records", "changed");
        let p = d.join("a.vdb");
        std::fs::write(&p, vec![7u8; 10_000]).unwrap();
        let f = crate::util::input_file::open(&p).unwrap();
        let len = f.metadata().unwrap().len();
        std::fs::OpenOptions::new().write(true).open(&p).unwrap().set_len(4096).unwrap();
        let e = read_exactly(&f, len).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
        assert!(e.to_string().contains("10000 bytes when opened, 4096 read"), "{e}");
        let e = VdbReadError::Io { path: p.clone(), source: e };
        assert!(!e.is_input(), "{e}");
        assert!(e.to_string().contains("a.vdb`: the file changed size while it was read"), "{e}");
        let f = crate::util::input_file::open(&p).unwrap();
        let e = read_exactly(&f, 100).unwrap_err();
        assert!(e.to_string().contains("100 bytes when opened, 101 read"), "{e}");
        assert!(!crate::util::input_file::is_input_io(&e));
        let f = crate::util::input_file::open(&p).unwrap();
        assert_eq!(read_exactly(&f, 4096).unwrap(), vec![7u8; 4096]);
        // A file that is missing, or not a regular file, stays the user's input.
        let missing = FileBytes::open(&d.join("missing.vdb")).err().unwrap();
        assert!(VdbReadError::Io { path: d.join("missing.vdb"), source: missing }.is_input());
        let dir = FileBytes::open(&d).err().unwrap();
        assert!(VdbReadError::Io { path: d.clone(), source: dir }.is_input());
        std::fs::remove_dir_all(&d).unwrap();
    }
}
