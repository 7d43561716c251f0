//! Text over the picture: the heads-up line (what is drawn and each step's time) and the help
//! overlay (`H`), in 8 × 8 glyphs (font8x8's public-domain ASCII set) drawn into the frame's
//! pixels on a darkened band. Only the window gets them: screenshots are the bare frame.

use font8x8::legacy::BASIC_LEGACY;

/// Pixels per glyph side.
const GLYPH: usize = 8;

/// An RGBA8 image the text is drawn into.
pub struct Canvas<'a> {
    /// Pixels, rows top to bottom.
    pub rgba: &'a mut [u8],
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
}

impl Canvas<'_> {
    /// Darkens the rectangle `x, y, w, h` (clipped to the image) to 35 % of its brightness.
    fn shade(&mut self, x: usize, y: usize, w: usize, h: usize) {
        for row in y..(y + h).min(self.height) {
            for col in x..(x + w).min(self.width) {
                let p = 4 * (row * self.width + col);
                for c in &mut self.rgba[p..p + 3] {
                    *c = (*c as u16 * 35 / 100) as u8;
                }
            }
        }
    }

    /// Writes `text` with its top-left corner at `x, y`, white; characters outside ASCII as `?`.
    fn text(&mut self, x: usize, y: usize, text: &str) {
        for (i, ch) in text.chars().enumerate() {
            let code = if ch.is_ascii() {
                ch as usize
            } else {
                b'?' as usize
            };
            let glyph = BASIC_LEGACY[code];
            for (gy, bits) in glyph.iter().enumerate() {
                for gx in 0..GLYPH {
                    let (px, py) = (x + i * GLYPH + gx, y + gy);
                    if bits >> gx & 1 == 1 && px < self.width && py < self.height {
                        let p = 4 * (py * self.width + px);
                        self.rgba[p..p + 3].copy_from_slice(&[235, 235, 235]);
                    }
                }
            }
        }
    }

    /// Lines of text on a dark band, from row `y`, with a 4-pixel margin.
    pub fn block(&mut self, y: usize, lines: &[String]) {
        if lines.is_empty() {
            return;
        }
        let longest = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0);
        let h = lines.len() * (GLYPH + 2) + 6;
        self.shade(0, y, longest * GLYPH + 8, h);
        for (i, line) in lines.iter().enumerate() {
            self.text(4, y + 4 + i * (GLYPH + 2), line);
        }
    }
}

/// The keys, as the help overlay lists them.
pub const HELP: &[&str] = &[
    "tessd view: keys (Blender's habits)",
    "middle-drag / left-drag  orbit     shift+middle-drag  pan",
    "wheel  zoom                        Home  frame everything",
    "1 3 7  front / right / top         9  opposite   5  ortho/persp",
    "W  solid > wireframe > points      E  edges      F  face ids",
    "C  cracks: none > image > object (B-Rep parts)",
    "+ / -  subdivision level (Catmull-Clark quads, Loop triangles)",
    "[ / ]  LOD level (built in the background on first use)",
    "P  clustering partition of the LOD   Space  play --frames",
    "F12  screenshot beside the input   H  this help   Esc  quit",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_lights_pixels_inside_its_band_only() {
        let (w, h) = (64, 32);
        let mut rgba = vec![200u8; w * h * 4];
        Canvas {
            rgba: &mut rgba,
            width: w,
            height: h,
        }
        .block(0, &["Hi".to_string()]);
        let lit = rgba.chunks(4).filter(|p| p[0] == 235).count();
        assert!(lit > 10, "{lit} glyph pixels");
        // the band is darkened, the rows below it are untouched
        assert_eq!(rgba[4 * (2 * w + 21)], 70);
        assert_eq!(rgba[4 * (31 * w + 5)], 200);
    }
}
