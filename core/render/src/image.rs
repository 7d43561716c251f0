//! PNG output: the colour image, and the face-id image in the exact encoding issue 21 fixes
//! for hosts — RGBA8 where `face index + 1 = R + 256·G + 65536·B`, 0 the background, A = 255 —
//! so any image library can read face ids back without tessd.

use crate::RenderError;
use std::io::Write;
use std::path::Path;

/// Face ids (+ 1, 0 the background) as RGBA8 pixels: R, G, B the id's low three bytes, A 255.
/// Ids of 2²⁴ or more do not fit and wrap (a part has far fewer faces).
pub fn face_ids_to_rgba(ids: &[u32]) -> Vec<u8> {
    ids.iter()
        .flat_map(|&id| [id as u8, (id >> 8) as u8, (id >> 16) as u8, 255])
        .collect()
}

/// The inverse of [`face_ids_to_rgba`]: `R + 256·G + 65536·B` of each pixel.
pub fn rgba_to_face_ids(rgba: &[u8]) -> Vec<u32> {
    rgba.chunks_exact(4)
        .map(|p| p[0] as u32 | (p[1] as u32) << 8 | (p[2] as u32) << 16)
        .collect()
}

/// Encodes `rgba` (`width × height` RGBA8 pixels, row 0 at the top) as a PNG into `out`.
///
/// # Errors
/// [`RenderError::Io`] when `out` fails (a full disk), [`RenderError::Png`] when the encoder
/// fails (or `rgba` has the wrong length).
pub fn encode_png(
    out: &mut dyn Write,
    width: u32,
    height: u32,
    rgba: &[u8],
) -> Result<(), RenderError> {
    let png_err = |e: png::EncodingError| match e {
        png::EncodingError::IoError(e) => RenderError::Io(e.to_string()),
        e => RenderError::Png(e.to_string()),
    };
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    // Renders are mostly flat areas: fast compression loses little against the default.
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().map_err(png_err)?;
    writer.write_image_data(rgba).map_err(png_err)?;
    writer.finish().map_err(png_err)
}

/// Writes `rgba` as a PNG file atomically (a temporary file renamed over `path`, so a failure
/// leaves no partial file).
///
/// # Errors
/// [`RenderError::Io`] naming `path` when the file cannot be written, [`RenderError::Png`] when
/// encoding fails.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), RenderError> {
    tessd_mesh::io::write_atomic(path, |w| {
        encode_png(w, width, height, rgba).map_err(|e| match e {
            RenderError::Io(e) => RenderError::Io(format!("{}: {e}", path.display())),
            e => e,
        })
    })
}

/// Decodes an 8-bit RGB or RGBA PNG into `(width, height, RGBA8 pixels)` (for tests and hosts
/// that check what was written).
///
/// # Errors
/// [`RenderError::Png`] for anything else.
pub fn decode_png(bytes: &[u8]) -> Result<(u32, u32, Vec<u8>), RenderError> {
    let png_err = |e: png::DecodingError| RenderError::Png(e.to_string());
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().map_err(png_err)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| RenderError::Png("the image is too large to decode".into()))?;
    let mut buf = vec![0; size];
    let info = reader.next_frame(&mut buf).map_err(png_err)?;
    buf.truncate(info.buffer_size());
    if info.bit_depth != png::BitDepth::Eight {
        return Err(RenderError::Png(format!(
            "bit depth {:?}, expected 8",
            info.bit_depth
        )));
    }
    let rgba = match info.color_type {
        png::ColorType::Rgba => buf,
        png::ColorType::Rgb => buf
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        other => {
            return Err(RenderError::Png(format!(
                "colour type {other:?}, expected RGB(A)"
            )));
        }
    };
    Ok((info.width, info.height, rgba))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn face_ids_round_trip_through_the_encoding() {
        let ids = [0, 1, 255, 256, 65_535, 65_536, 0x00ab_cdef];
        let rgba = face_ids_to_rgba(&ids);
        assert_eq!(&rgba[4..8], &[1, 0, 0, 255]);
        assert_eq!(&rgba[12..16], &[0, 1, 0, 255]);
        assert_eq!(&rgba[20..24], &[0, 0, 1, 255]);
        assert_eq!(rgba_to_face_ids(&rgba), ids);
    }

    #[test]
    fn png_round_trips() {
        let rgba: Vec<u8> = (0..3 * 2 * 4).map(|i| (i * 7) as u8).collect();
        let mut bytes = Vec::new();
        encode_png(&mut bytes, 3, 2, &rgba).unwrap();
        assert_eq!(decode_png(&bytes).unwrap(), (3, 2, rgba));
        assert!(encode_png(&mut Vec::new(), 3, 3, &[0; 8]).is_err());
    }
}
