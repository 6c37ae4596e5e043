//! PNG map images, decoded into the same raster as PGM files.

use std::path::Path;

use super::Raster;
use crate::{OccupancyError, Result};

/// Decodes a PNG map image (grey, grey + alpha, RGB or RGBA; 8 or 16 bits).
pub(crate) fn decode_png_raster(bytes: &[u8], path: &Path) -> Result<Raster> {
    let err = |message: String| OccupancyError::Png {
        path: path.to_path_buf(),
        message,
    };
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| err(e.to_string()))?;
    // A palette of partial RGB entries (or more than 256 of them), or transparency for more
    // entries than the palette has, is refused here: `png` 0.18 panics on the first when it
    // expands the indices (found by the `map_image` fuzz target).
    if let Some(palette) = &reader.info().palette {
        let entries = palette.len() / 3;
        if palette.len() % 3 != 0 || entries == 0 || entries > 256 {
            return Err(err(format!(
                "palette of {} bytes: not 1 to 256 whole RGB entries",
                palette.len()
            )));
        }
        if let Some(trns) = &reader.info().trns
            && reader.info().color_type == png::ColorType::Indexed
            && trns.len() > entries
        {
            return Err(err(format!(
                "transparency for {} palette entries, the palette has {entries}",
                trns.len()
            )));
        }
    }
    let (width, height) = (reader.info().width as usize, reader.info().height as usize);
    if width == 0 || height == 0 {
        return Err(OccupancyError::BadGridSize { width, height });
    }
    // The cell budget, in pixels, before the image buffer is allocated (the resolution and
    // area are the map file's, not known here: one pixel a side).
    let (w, h) = (width as f64, height as f64);
    crate::budget::check_extent(
        w,
        h,
        1.0,
        nalgebra::Point2::origin(),
        nalgebra::Point2::new(w, h),
    )?;
    // Deflate expands data at most 1032-fold and EXPAND widens samples at most 8-fold: a
    // header announcing more than that is a truncated or forged file, refused before the
    // buffer is allocated.
    let plausible = bytes.len().saturating_mul(1032 * 8).saturating_add(1 << 16);
    let size = reader
        .output_buffer_size()
        .filter(|&n| n <= plausible)
        .ok_or_else(|| {
            err(format!(
                "header announces {width}×{height} pixels, more than {} bytes of PNG can hold",
                bytes.len()
            ))
        })?;
    let mut buf = vec![0; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| err(e.to_string()))?;
    let channels = info.color_type.samples();
    let samples: Vec<u16> = match info.bit_depth {
        png::BitDepth::Sixteen => buf[..info.buffer_size()]
            .chunks_exact(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect(),
        _ => buf[..info.buffer_size()]
            .iter()
            .map(|&b| u16::from(b))
            .collect(),
    };
    let maxval = if info.bit_depth == png::BitDepth::Sixteen {
        65535
    } else {
        255
    };
    Ok(Raster {
        width: info.width as usize,
        height: info.height as usize,
        maxval,
        channels,
        samples,
    })
}
