//! A VDB file's leaf records, read where they lie: the file's bytes
//! ([`FileBytes`], mapped where the system allows) and one grid's located
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

/// A file's bytes: mapped into memory where the system allows (the pages
/// come straight from the page cache: no copy of a 190 MB file, a fault
/// per 64 KiB instead of per 4 KiB), else read.
///
/// The map is private and read-only. If another process truncates the
/// file while it is mapped, reading the lost pages raises SIGBUS, as with
/// any mapped file (OpenVDB maps its files the same way, with
/// `boost::interprocess`); aurora never writes a file in place (its
/// outputs are staged and renamed, `crate::util::atomic_write`), so its own writes
/// cannot do this to a file being read.
pub enum FileBytes {
    #[cfg(unix)]
    Mapped {
        ptr: *mut libc::c_void,
        len: usize,
    },
    Read(Vec<u8>),
}

impl FileBytes {
    /// The bytes of the regular file at `path`.
    pub fn open(path: &Path) -> std::io::Result<FileBytes> {
        // Only a regular file is mapped or read (`crate::util::input_file`).
        let file = crate::util::input_file::open(path)?;
        let len = file.metadata()?.len();
        #[cfg(unix)]
        if len > 0 && len <= isize::MAX as u64 {
            use std::os::fd::AsRawFd;
            let len = len as usize;
            // SAFETY: a fresh private read-only mapping of `len` bytes of an
            // open file; the result is checked against MAP_FAILED.
            let ptr = unsafe { libc::mmap(std::ptr::null_mut(), len, libc::PROT_READ, libc::MAP_PRIVATE, file.as_raw_fd(), 0) };
            if ptr != libc::MAP_FAILED {
                return Ok(FileBytes::Mapped { ptr, len });
            }
        }
        let mut bytes = Vec::with_capacity(len as usize);
        std::io::Read::read_to_end(&mut &file, &mut bytes)?;
        Ok(FileBytes::Read(bytes))
    }

    /// The file's bytes.
    pub fn bytes(&self) -> &[u8] {
        match self {
            // SAFETY: the mapping is `len` readable bytes, alive until drop.
            #[cfg(unix)]
            FileBytes::Mapped { ptr, len } => unsafe { std::slice::from_raw_parts(ptr.cast::<u8>(), *len) },
            FileBytes::Read(b) => b,
        }
    }
}

impl Drop for FileBytes {
    fn drop(&mut self) {
        #[cfg(unix)]
        if let FileBytes::Mapped { ptr, len } = self {
            // SAFETY: unmaps exactly the mapping made in `open`, once.
            unsafe { libc::munmap(*ptr, *len) };
        }
    }
}
