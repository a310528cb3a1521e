//! A sequence's USD stage at the longest ranges (`src/io/usd.rs`): its
//! writer streams, handing its sink one line at a time however many frames
//! the stage lists, so a task's memory does not grow with the range (a
//! stage of ten million frames is about 900 MB of text); the streamed
//! bytes are the text the stage has always had, and the file written
//! through a buffered temporary holds them.

use crate::common::scratch;
use aurora::io::usd::{usda_sequence_text, write_usda_sequence, write_usda_sequence_into, Sequence};
use std::io::Write;

/// A sink that keeps no bytes: it counts them and remembers the largest
/// single write.
#[derive(Default)]
struct Counting {
    bytes: u64,
    writes: u64,
    largest: usize,
}

impl Write for Counting {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.bytes += buf.len() as u64;
        self.writes += 1;
        self.largest = self.largest.max(buf.len());
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fn name(f: i64) -> String {
    aurora::farm::frame_range::frame_file_name("aurora", f, "vdb")
}

const FIELDS: [(&str, &str); 2] = [("density", "float"), ("emission", "float3")];

/// Two million frames: the sink never receives more than a line (under
/// 200 bytes; a writer that formats the stage first and writes it whole
/// hands over 150 MB at once), and the count matches what the farm's
/// plan counts for the same range.
#[test]
fn a_long_stage_reaches_its_sink_a_line_at_a_time() {
    let frames: Vec<i64> = (0..2_000_000).collect();
    let mut sink = Counting::default();
    write_usda_sequence_into(&mut sink, Sequence { frames: &frames, name: &name, fps: 24.0 }, &FIELDS, 1000.0).unwrap();
    println!("{} bytes in {} writes, the largest {} bytes", sink.bytes, sink.writes, sink.largest);
    assert!(sink.bytes > 2 * 2_000_000 * 30, "every frame listed once per field: {} bytes", sink.bytes);
    assert!(sink.largest < 200, "a write of {} bytes: the stage was not streamed", sink.largest);
    let fields: Vec<(String, &'static str)> = FIELDS.iter().map(|(n, t)| (n.to_string(), *t)).collect();
    assert_eq!(aurora::farm::frame_files::sequence_usda_bytes(&frames, 24.0, &fields).unwrap(), sink.bytes);
}

/// The streamed bytes are the stage's text, and the file written through
/// the buffered temporary holds exactly them and nothing else is left.
#[test]
fn a_streamed_stage_is_the_same_text_in_a_sink_and_in_its_file() {
    let frames: Vec<i64> = (0..50_000).map(|k| 3 * k + 7).collect();
    let seq = Sequence { frames: &frames, name: &name, fps: 30.0 };
    let text = usda_sequence_text(seq, &FIELDS, 1000.0);
    let mut bytes = Vec::new();
    write_usda_sequence_into(&mut bytes, seq, &FIELDS, 1000.0).unwrap();
    assert!(bytes == text.as_bytes());
    assert!(text.contains("            7: @aurora.0007.vdb@,\n") && text.contains("150004: @aurora.150004.vdb@,\n"));
    let dir = scratch("stage", "file");
    let path = dir.join("aurora.usda");
    write_usda_sequence(&path, seq, &FIELDS, 1000.0).unwrap();
    assert!(std::fs::read(&path).unwrap() == bytes);
    assert_eq!(crate::common::file_names(&dir), ["aurora.usda"]);
}
