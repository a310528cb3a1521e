//! Image files: the linear OpenEXR result and an 8-bit PNG preview.
//!
//! * EXR: 32-bit float RGBA, linear Rec.709 (chromaticities attribute set to
//!   Rec.709 primaries and D65 white), row 0 at the top, `A = 1 - T` (the
//!   volume's coverage along the primary ray; RGB already contains what lies
//!   behind). Lossless compression (the `exr` crate's default, RLE in 64x64
//!   tiles), tiles stored in increasing order (`LineOrder::Increasing`): the
//!   crate compresses tiles in parallel, and in its default "unspecified"
//!   order it would write them as they finish, the same image in different
//!   bytes from run to run.
//! * PNG preview: 8-bit sRGB RGB of `2^exposure * linear` through the view
//!   transform (`view_transform.rs`); alpha is dropped.
//! * One-channel images of a float grid (`aurora render --grid`): the red
//!   channel (the grid is rendered as grey) as an EXR of one 32-bit float
//!   channel `Y` in the grid's units integrated along the ray (rayleigh for
//!   a per-line grid in R/km), or an 8-bit greyscale PNG, linear:
//!   `round(255 clamp(v / scale, 0, 1))`, the scale stated by the caller
//!   and stored in the PNG's `aurora_scale` text chunk. Both carry what
//!   the values are ([`GreyMetadata`]): the units (`aurora_units`) and
//!   whether the air's extinction is in them (`aurora_air`), as EXR header
//!   attributes of type string (`aurora_units` among the image's, `aurora_air`
//!   among the layer's: the crate keeps each set in a hash map, so one
//!   attribute in each keeps the header's bytes in one order) and as PNG
//!   `tEXt` chunks.
//!
//! All are written to a temporary file in the destination folder and renamed.
//!
//! An EXR is read ([`read_exr`], the sky's background image) only once the
//! sizes its headers declare are checked against the file's length and the
//! process's memory ([`check_exr_size`]): a damaged size is refused (exit
//! status 2), never allocated.

use super::image::{Image, RenderStats};
use super::settings::RenderError;
use super::view_transform::{display_rgb, display_rgb16};
use crate::scene::ViewTransform;
use exr::prelude::{read, ReadChannels, ReadLayers, SpecificChannels, Vec2, WritableImage};
use std::path::Path;

fn output_err(e: crate::util::atomic_write::AtomicError) -> RenderError {
    RenderError::Output(Box::new(e))
}

/// Writes a one-layer EXR image to a temporary in `path`'s folder, tiles in
/// increasing order (module documentation: the same bytes every run), and
/// renames it to `path`.
fn write_exr_image<'i, C>(path: &Path, exr_image: &'i mut exr::image::Image<exr::image::Layer<C>>) -> Result<(), RenderError>
where
    exr::image::Layer<C>: exr::image::write::layers::WritableLayers<'i>,
{
    exr_image.layer_data.encoding.line_order = exr::meta::attribute::LineOrder::Increasing;
    let exr_image: &'i exr::image::Image<_> = exr_image;
    let mut tmp = crate::util::atomic_write::TempFile::create(path).map_err(output_err)?;
    exr_image
        .write()
        .to_buffered(std::io::BufWriter::new(tmp.file()))
        .map_err(|e| RenderError::Exr { path: path.to_path_buf(), message: e.to_string() })?;
    tmp.commit().map_err(output_err)
}

/// Writes `image` as a linear Rec.709 RGBA f32 OpenEXR.
pub fn write_exr(path: impl AsRef<Path>, image: &Image) -> Result<(), RenderError> {
    write_exr_with(path, image, &[])
}

/// [`write_exr`] with `meta`'s (key, text) pairs among the image's string
/// attributes (how its PNG was developed: `crate::render::develop`).
pub fn write_exr_with(path: impl AsRef<Path>, image: &Image, meta: &[(String, String)]) -> Result<(), RenderError> {
    let path = path.as_ref();
    let (w, h) = (image.width, image.height);
    if image.pixels.len() != w * h || w == 0 || h == 0 {
        return Err(RenderError::Settings(format!("image of {}x{} has {} pixels", w, h, image.pixels.len())));
    }
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let p = image.pixels[y * w + x];
        (p[0], p[1], p[2], p[3])
    });
    let mut exr_image = exr::image::Image::from_channels((w, h), channels);
    exr_image.attributes.chromaticities = Some(exr::meta::attribute::Chromaticities {
        red: Vec2(0.64, 0.33),
        green: Vec2(0.30, 0.60),
        blue: Vec2(0.15, 0.06),
        white: Vec2(0.3127, 0.3290),
    });
    for (k, v) in meta {
        use exr::meta::attribute::{AttributeValue, Text};
        exr_image.attributes.other.insert(Text::from(k.as_str()), AttributeValue::Text(Text::from(v.as_str())));
    }
    write_exr_image(path, &mut exr_image)
}

/// What a one-channel image's values are (module doc): written into its
/// EXR header and PNG text chunks.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GreyMetadata {
    /// `aurora_units`: the values' units and how they were made.
    pub units: String,
    /// `aurora_air`: whether the air's extinction is applied.
    pub air: String,
}

/// Writes the red channel of `image` as a one-channel (`Y`) f32 OpenEXR
/// (module doc), with `meta` in its header when given.
pub fn write_exr_grey(path: impl AsRef<Path>, image: &Image, meta: Option<&GreyMetadata>) -> Result<(), RenderError> {
    let path = path.as_ref();
    let (w, h) = (image.width, image.height);
    if image.pixels.len() != w * h || w == 0 || h == 0 {
        return Err(RenderError::Settings(format!("image of {}x{} has {} pixels", w, h, image.pixels.len())));
    }
    let channels = SpecificChannels::build().with_channel("Y").with_pixel_fn(|Vec2(x, y): Vec2<usize>| (image.pixels[y * w + x][0],));
    let mut exr_image = exr::image::Image::from_channels((w, h), channels);
    if let Some(m) = meta {
        use exr::meta::attribute::{AttributeValue, Text};
        exr_image.attributes.other.insert(Text::from("aurora_units"), AttributeValue::Text(Text::from(m.units.as_str())));
        exr_image.layer_data.attributes.other.insert(Text::from("aurora_air"), AttributeValue::Text(Text::from(m.air.as_str())));
    }
    write_exr_image(path, &mut exr_image)
}

/// The string attributes of an EXR's first header (the image's and the
/// first layer's), sorted by name.
pub fn read_exr_text_attributes(path: impl AsRef<Path>) -> Result<Vec<(String, String)>, RenderError> {
    let path = path.as_ref();
    let file = crate::util::input_file::open(path).map_err(|e| RenderError::Exr { path: path.to_path_buf(), message: e.reason() })?;
    let meta = exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(file), false)
        .map_err(|e| RenderError::Exr { path: path.to_path_buf(), message: e.to_string() })?;
    let mut out = Vec::new();
    if let Some(h) = meta.headers.first() {
        for (k, v) in h.shared_attributes.other.iter().chain(h.own_attributes.other.iter()) {
            if let exr::meta::attribute::AttributeValue::Text(t) = v {
                out.push((k.to_string(), t.to_string()));
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Reads the `Y` channel of a one-channel EXR written by [`write_exr_grey`]:
/// (width, height, values row by row from the top).
pub fn read_exr_grey(path: impl AsRef<Path>) -> Result<(usize, usize, Vec<f32>), RenderError> {
    use exr::prelude::ReadSpecificChannel;
    let path = path.as_ref();
    let file = crate::util::input_file::open(path).map_err(|e| RenderError::Exr { path: path.to_path_buf(), message: e.reason() })?;
    check_exr_size(&file, path, 4)?;
    let channels = read().no_deep_data().largest_resolution_level().specific_channels().required("Y").collect_pixels(
        |res: Vec2<usize>, _| (res.0, vec![0.0f32; res.0 * res.1]),
        |(w, px): &mut (usize, Vec<f32>), pos: Vec2<usize>, (y,): (f32,)| px[pos.1 * *w + pos.0] = y,
    );
    let layer = first_valid_layer(channels, file, path)?;
    let (_, values) = layer.channel_data.pixels;
    Ok((layer.size.0, layer.size.1, values))
}

/// Bytes a reader may hold per pixel of an image it reads, for each byte
/// of the pixels it returns: the decoded blocks beside the returned image,
/// and the caller's own copy (the sky's map of the background).
const EXR_READ_COPIES: u64 = 3;

/// Most bytes of samples an EXR's file may hold per byte of file: above
/// the highest ratio of any of OpenEXR's compressions (ZIP's deflate
/// reaches about 1032, PXR24's a third more, RLE 64).
const MAX_EXR_RATIO: u128 = 2048;

/// Checks the sizes an EXR's headers declare before any pixel is allocated
/// : the offset table of every layer (eight bytes per block of
/// pixels, all in the file) fits in the file's length, and the largest
/// layer's samples fit in [`MAX_EXR_RATIO`] times the file's length, and
/// its pixels at `bytes_per_pixel` (the image the reader returns),
/// [`EXR_READ_COPIES`] times, fit in the memory this process may use
/// ([`crate::util::memory::available`]). A header that declares 100000 x
/// 100000 pixels in a file of a few hundred bytes is refused here, naming
/// both, instead of ending the process in a failed allocation. The file is
/// left at its start for the reader.
pub fn check_exr_size(file: &std::fs::File, path: &Path, bytes_per_pixel: u64) -> Result<(), RenderError> {
    use std::io::{Seek, SeekFrom};
    let exr_err = |message: String| RenderError::Exr { path: path.to_path_buf(), message };
    let refuse = |message: String| RenderError::ImageSize { path: path.to_path_buf(), message };
    let file_len = file.metadata().map_err(|e| exr_err(e.to_string()))?.len();
    let meta = exr::meta::MetaData::read_from_buffered(std::io::BufReader::new(file), false).map_err(|e| exr_err(e.to_string()))?;
    let blocks: u128 = meta.headers.iter().map(|h| h.chunk_count as u128).sum();
    if blocks * 8 > file_len as u128 {
        return Err(refuse(format!(
            "its headers declare {blocks} blocks of pixels, whose offsets alone (8 bytes each) would not fit in the file's {file_len} bytes: \
             the file is damaged or truncated"
        )));
    }
    let limit = crate::util::memory::available();
    for h in meta.headers.iter() {
        let (w, hgt) = (h.layer_size.0 as u128, h.layer_size.1 as u128);
        let stored = w * hgt * h.channels.bytes_per_pixel as u128;
        if stored > file_len as u128 * MAX_EXR_RATIO {
            return Err(refuse(format!(
                "its image of {w} x {hgt} pixels holds {stored} bytes of samples, more than {MAX_EXR_RATIO} times the file's {file_len} bytes, \
                 beyond what any of OpenEXR's compressions reaches: the file is damaged or truncated"
            )));
        }
        let needed = w * hgt * bytes_per_pixel as u128 * EXR_READ_COPIES as u128;
        if needed as f64 > limit.bytes {
            return Err(refuse(format!(
                "its image of {w} x {hgt} pixels would need about {} to read, but this process may use {limit}",
                crate::util::memory::gib(needed as f64)
            )));
        }
    }
    let mut f = file;
    f.seek(SeekFrom::Start(0)).map_err(|e| exr_err(e.to_string()))?;
    Ok(())
}

/// The first valid layer of the EXR `file` (named `path` in errors) as
/// `channels` reads it, with all its attributes.
fn first_valid_layer<C, Channels>(channels: C, file: std::fs::File, path: &Path) -> Result<exr::image::Layer<Channels>, RenderError>
where
    C: for<'s> ReadChannels<'s>,
    exr::image::read::layers::ReadFirstValidLayer<C>: for<'s> ReadLayers<'s, Layers = exr::image::Layer<Channels>>,
{
    let img = channels
        .first_valid_layer()
        .all_attributes()
        .from_unbuffered(file)
        .map_err(|e| RenderError::Exr { path: path.to_path_buf(), message: e.to_string() })?;
    Ok(img.layer_data)
}

/// Writes the red channel of `image` as an 8-bit greyscale PNG, linear with
/// 255 = `scale` (module doc; `scale` > 0 and finite), with `meta` in text
/// chunks when given.
pub fn write_png_grey(path: impl AsRef<Path>, image: &Image, scale: f64, meta: Option<&GreyMetadata>) -> Result<(), RenderError> {
    let path = path.as_ref();
    let (w, h) = (image.width, image.height);
    if image.pixels.len() != w * h || w == 0 || h == 0 {
        return Err(RenderError::Settings(format!("image of {}x{} has {} pixels", w, h, image.pixels.len())));
    }
    if !(scale.is_finite() && scale > 0.0) {
        return Err(RenderError::Settings(format!("greyscale scale {scale} must be finite and > 0")));
    }
    let data: Vec<u8> = image
        .pixels
        .iter()
        .map(|p| {
            let v = p[0] as f64 / scale;
            (if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) } * 255.0).round() as u8
        })
        .collect();
    let mut tmp = crate::util::atomic_write::TempFile::create(path).map_err(output_err)?;
    let png_err = |m: String| RenderError::Png { path: path.to_path_buf(), message: m };
    let r = (|| -> Result<(), RenderError> {
        let mut enc = png::Encoder::new(std::io::BufWriter::new(tmp.file()), w as u32, h as u32);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        enc.add_text_chunk("aurora_scale".into(), format!("255 = {scale:e} (linear)")).map_err(|e| png_err(e.to_string()))?;
        if let Some(m) = meta {
            enc.add_text_chunk("aurora_units".into(), m.units.clone()).map_err(|e| png_err(e.to_string()))?;
            enc.add_text_chunk("aurora_air".into(), m.air.clone()).map_err(|e| png_err(e.to_string()))?;
        }
        let mut writer = enc.write_header().map_err(|e| png_err(e.to_string()))?;
        writer.write_image_data(&data).map_err(|e| png_err(e.to_string()))?;
        writer.finish().map_err(|e| png_err(e.to_string()))
    })();
    r?;
    tmp.commit().map_err(output_err)
}

/// Reads the first RGBA layer of an EXR (alpha 1 if absent). Stats are zero.
pub fn read_exr(path: impl AsRef<Path>) -> Result<Image, RenderError> {
    let path = path.as_ref();
    let file = crate::util::input_file::open(path).map_err(|e| RenderError::Exr { path: path.to_path_buf(), message: e.reason() })?;
    read_exr_file(file, path)
}

/// [`read_exr`] of a file already opened (through `crate::util::input_file`);
/// `path` names it in errors.
pub fn read_exr_file(file: std::fs::File, path: &Path) -> Result<Image, RenderError> {
    check_exr_size(&file, path, std::mem::size_of::<[f32; 4]>() as u64)?;
    let channels = read().no_deep_data().largest_resolution_level().rgba_channels(
        |res: Vec2<usize>, _| (res.0, vec![[0.0f32; 4]; res.0 * res.1]),
        |(w, px): &mut (usize, Vec<[f32; 4]>), pos: Vec2<usize>, (r, g, b, a): (f32, f32, f32, f32)| {
            px[pos.1 * *w + pos.0] = [r, g, b, a];
        },
    );
    let layer = first_valid_layer(channels, file, path)?;
    let (_, pixels) = layer.channel_data.pixels;
    Ok(Image { width: layer.size.0, height: layer.size.1, pixels, stats: RenderStats::default() })
}

/// Writes an 8-bit sRGB PNG preview through the view transform (module doc).
pub fn write_png(path: impl AsRef<Path>, image: &Image, exposure: f64, view: ViewTransform) -> Result<(), RenderError> {
    write_png_bits(path, image, exposure, view, PngBits::Eight)
}

/// Bits per channel of a PNG: 8 for previews, 16 for delivery (a dome
/// master's frames, which 8 bits band in the faint gradients of the sky).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PngBits {
    Eight,
    Sixteen,
}

/// Writes an sRGB PNG of `bits` per channel through the view transform
/// (module doc); 16-bit samples big-endian, as PNG stores them.
pub fn write_png_bits(path: impl AsRef<Path>, image: &Image, exposure: f64, view: ViewTransform, bits: PngBits) -> Result<(), RenderError> {
    write_png_with(path, image, exposure, view, bits, &[])
}

/// [`write_png_bits`] with `meta`'s (key, text) pairs in text chunks (how
/// it was developed: `crate::render::develop`).
pub fn write_png_with(
    path: impl AsRef<Path>,
    image: &Image,
    exposure: f64,
    view: ViewTransform,
    bits: PngBits,
    meta: &[(String, String)],
) -> Result<(), RenderError> {
    let path = path.as_ref();
    let (w, h) = (image.width, image.height);
    if image.pixels.len() != w * h || w == 0 || h == 0 {
        return Err(RenderError::Settings(format!("image of {}x{} has {} pixels", w, h, image.pixels.len())));
    }
    if !exposure.is_finite() {
        return Err(RenderError::Settings(format!("exposure {exposure} must be finite")));
    }
    let data: Vec<u8> = match bits {
        PngBits::Eight => image.pixels.iter().flat_map(|&p| display_rgb(p, exposure, view)).collect(),
        PngBits::Sixteen => image.pixels.iter().flat_map(|&p| display_rgb16(p, exposure, view)).flat_map(u16::to_be_bytes).collect(),
    };
    let mut tmp = crate::util::atomic_write::TempFile::create(path).map_err(output_err)?;
    let png_err = |m: String| RenderError::Png { path: path.to_path_buf(), message: m };
    let r = (|| -> Result<(), RenderError> {
        let mut enc = png::Encoder::new(std::io::BufWriter::new(tmp.file()), w as u32, h as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(match bits {
            PngBits::Eight => png::BitDepth::Eight,
            PngBits::Sixteen => png::BitDepth::Sixteen,
        });
        enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
        for (k, v) in meta {
            enc.add_text_chunk(k.clone(), v.clone()).map_err(|e| png_err(e.to_string()))?;
        }
        let mut writer = enc.write_header().map_err(|e| png_err(e.to_string()))?;
        writer.write_image_data(&data).map_err(|e| png_err(e.to_string()))?;
        writer.finish().map_err(|e| png_err(e.to_string()))
    })();
    r?;
    tmp.commit().map_err(output_err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::scratch::folder;

    /// A small EXR whose header is changed to declare 100000 x 100000
    /// pixels is refused by its sizes (an input error naming the file and
    /// the counts), before any pixel is allocated; the file as written
    /// still reads.
    #[test]
    fn an_exr_declaring_more_pixels_than_its_file_holds_is_refused() {
        let d = folder("image-file", "declared");
        let p = d.join("sky.exr");
        let pixels = (0..16).map(|i| [i as f32, 0.5, 0.25, 1.0]).collect();
        write_exr(&p, &Image { width: 4, height: 4, pixels, stats: RenderStats::default() }).unwrap();
        assert_eq!(read_exr(&p).unwrap().pixels.len(), 16);
        let mut bytes = std::fs::read(&p).unwrap();
        let key = b"dataWindow\0box2i\0";
        let at = bytes.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
        for (i, v) in [0i32, 0, 99_999, 99_999].into_iter().enumerate() {
            bytes[at + 4 * i..at + 4 * i + 4].copy_from_slice(&v.to_le_bytes());
        }
        std::fs::write(&p, &bytes).unwrap();
        let e = read_exr(&p).unwrap_err();
        assert!(matches!(e, RenderError::ImageSize { .. }) && e.is_input(), "{e:?}");
        let m = e.to_string();
        assert!(m.starts_with(&p.display().to_string()) && m.contains(&format!("the file's {} bytes", bytes.len())), "{m}");
        std::fs::remove_dir_all(&d).unwrap();
    }
}
