//! Joins PNG frames of equal size into one animated PNG (APNG), looping:
//! the README's animation of the default scene.
//!
//!   cargo run --release --example apng -- OUT.png DELAY_MS FRAME1.png FRAME2.png ...

use std::fs::File;
use std::io::BufWriter;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    anyhow::ensure!(args.len() >= 3, "usage: apng OUT.png DELAY_MS FRAME.png...");
    let delay: u16 = args[1].parse()?;
    let mut frames = Vec::new();
    let mut size = None;
    for p in &args[2..] {
        let mut reader = png::Decoder::new(File::open(p)?).read_info()?;
        let mut buf = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut buf)?;
        buf.truncate(info.buffer_size());
        let s = (info.width, info.height, info.color_type, info.bit_depth);
        anyhow::ensure!(size.is_none_or(|z| z == s), "{p}: size or format differs from the first frame");
        size = Some(s);
        frames.push(buf);
    }
    let (w, h, colour, depth) = size.expect("at least one frame");
    let out = args[0].clone();
    let tmp = format!("{out}.tmp");
    {
        let mut enc = png::Encoder::new(BufWriter::new(File::create(&tmp)?), w, h);
        enc.set_color(colour);
        enc.set_depth(depth);
        enc.set_animated(frames.len() as u32, 0)?;
        enc.set_frame_delay(delay, 1000)?;
        let mut writer = enc.write_header()?;
        for f in &frames {
            writer.write_image_data(f)?;
        }
        writer.finish()?;
    }
    std::fs::rename(&tmp, &out)?;
    eprintln!("wrote {out}: {} frames, {w}x{h}, {delay} ms each", frames.len());
    Ok(())
}
