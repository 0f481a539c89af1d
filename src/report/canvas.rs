//! The pixel buffer the pictures are drawn into: 8-bit RGB, drawn on
//! through embedded-graphics (lines, circles, rectangles and its bundled
//! bitmap fonts) and encoded as PNG bytes. Nothing here touches a file.

use std::convert::Infallible;

use embedded_graphics::mono_font::{MonoFont, MonoTextStyle};
use embedded_graphics::pixelcolor::Rgb888;
use embedded_graphics::prelude::*;
use embedded_graphics::primitives::{Circle, Line, PrimitiveStyle, PrimitiveStyleBuilder, Rectangle};
use embedded_graphics::text::{Baseline, Text};

/// How far outside the canvas, in pixels, a shape's points may lie and the
/// shape still be drawn. A projected point can land arbitrarily far away
/// (a point near the camera's plane), and embedded-graphics walks every
/// pixel of a line, on the canvas or not: beyond this the shape is left
/// out rather than walked for millions of pixels.
const MAX_OFF_CANVAS_PX: f64 = 4096.0;

/// An RGB picture.
#[derive(Debug, Clone, PartialEq)]
pub struct Canvas {
    width: u32,
    height: u32,
    /// Row-major RGB triples.
    rgb: Vec<u8>,
}

impl Canvas {
    /// A canvas filled with `background`.
    pub fn new(width: u32, height: u32, background: Rgb888) -> Self {
        let rgb = [background.r(), background.g(), background.b()].repeat(width as usize * height as usize);
        Canvas { width, height, rgb }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// The colour at `(x, y)`, if that is on the canvas.
    pub fn pixel(&self, x: u32, y: u32) -> Option<Rgb888> {
        (x < self.width && y < self.height).then(|| {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            Rgb888::new(self.rgb[i], self.rgb[i + 1], self.rgb[i + 2])
        })
    }

    /// Sets `(x, y)` when it is on the canvas.
    pub fn set(&mut self, x: i64, y: i64, colour: Rgb888) {
        if (0..self.width as i64).contains(&x) && (0..self.height as i64).contains(&y) {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            self.rgb[i..i + 3].copy_from_slice(&[colour.r(), colour.g(), colour.b()]);
        }
    }

    /// Copies `other` onto this canvas with its top-left corner at `(x, y)`.
    pub fn paste(&mut self, other: &Canvas, x: i64, y: i64) {
        for row in 0..other.height {
            for col in 0..other.width {
                if let Some(c) = other.pixel(col, row) {
                    self.set(x + col as i64, y + row as i64, c);
                }
            }
        }
    }

    /// The picture as PNG bytes.
    pub fn encode_png(&self) -> Result<Vec<u8>, png::EncodingError> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        encoder.set_compression(png::Compression::Balanced);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&self.rgb)?;
        writer.finish()?;
        Ok(bytes)
    }

    /// A straight line `width` pixels wide.
    pub fn line(&mut self, a: (f64, f64), b: (f64, f64), colour: Rgb888, width: u32) {
        if self.near(a) && self.near(b) {
            let _ = Line::new(point(a), point(b)).into_styled(PrimitiveStyle::with_stroke(colour, width)).draw(self);
        }
    }

    /// A polyline through `points`, `width` pixels wide.
    pub fn polyline(&mut self, points: &[(f64, f64)], colour: Rgb888, width: u32) {
        for pair in points.windows(2) {
            self.line(pair[0], pair[1], colour, width);
        }
    }

    /// A disc of `diameter` pixels centred at `at`, with a one-pixel
    /// outline when `outline` is given.
    pub fn disc(&mut self, at: (f64, f64), diameter: u32, fill: Rgb888, outline: Option<Rgb888>) {
        if !self.near(at) {
            return;
        }
        let style = match outline {
            Some(o) => PrimitiveStyleBuilder::new().fill_color(fill).stroke_color(o).stroke_width(1).build(),
            None => PrimitiveStyle::with_fill(fill),
        };
        let _ = Circle::with_center(point(at), diameter).into_styled(style).draw(self);
    }

    /// A ring of `diameter` pixels, `width` pixels thick, centred at `at`.
    pub fn ring(&mut self, at: (f64, f64), diameter: u32, colour: Rgb888, width: u32) {
        if self.near(at) {
            let _ = Circle::with_center(point(at), diameter)
                .into_styled(PrimitiveStyle::with_stroke(colour, width))
                .draw(self);
        }
    }

    /// A filled rectangle.
    pub fn fill_rect(&mut self, x: i64, y: i64, width: u32, height: u32, colour: Rgb888) {
        let rect = Rectangle::new(Point::new(x as i32, y as i32), Size::new(width, height));
        let _ = rect.into_styled(PrimitiveStyle::with_fill(colour)).draw(self);
    }

    /// A rectangle's outline, one pixel wide.
    pub fn frame_rect(&mut self, x: i64, y: i64, width: u32, height: u32, colour: Rgb888) {
        let rect = Rectangle::new(Point::new(x as i32, y as i32), Size::new(width, height));
        let _ = rect.into_styled(PrimitiveStyle::with_stroke(colour, 1)).draw(self);
    }

    /// `text` in `font` with its top-left corner at `(x, y)`; returns the
    /// x just past its end.
    pub fn text(&mut self, text: &str, x: i64, y: i64, font: &MonoFont, colour: Rgb888) -> i64 {
        let style = MonoTextStyle::new(font, colour);
        let at = Point::new(x as i32, y as i32);
        Text::with_baseline(text, at, style, Baseline::Top).draw(self).map_or(x, |end| i64::from(end.x))
    }

    /// Whether `p` is close enough to the canvas to draw a shape at.
    fn near(&self, (x, y): (f64, f64)) -> bool {
        let margin = MAX_OFF_CANVAS_PX;
        (-margin..f64::from(self.width) + margin).contains(&x)
            && (-margin..f64::from(self.height) + margin).contains(&y)
    }
}

fn point((x, y): (f64, f64)) -> Point {
    Point::new(x.round() as i32, y.round() as i32)
}

/// The width of `text` in `font`, pixels.
pub fn text_width(text: &str, font: &MonoFont) -> u32 {
    let glyph = font.character_size.width + font.character_spacing;
    text.chars().count() as u32 * glyph
}

/// `text` broken at spaces into lines of at most `max_chars` characters
/// (a longer word stands on a line of its own, cut to fit).
pub fn wrap(text: &str, max_chars: usize) -> Vec<String> {
    let max_chars = max_chars.max(1);
    let mut lines: Vec<String> = Vec::new();
    let mut line = String::new();
    for word in text.split_whitespace() {
        let word: String = word.chars().take(max_chars).collect();
        if !line.is_empty() && line.chars().count() + 1 + word.chars().count() > max_chars {
            lines.push(std::mem::take(&mut line));
        }
        if !line.is_empty() {
            line.push(' ');
        }
        line.push_str(&word);
    }
    if !line.is_empty() {
        lines.push(line);
    }
    lines
}

impl OriginDimensions for Canvas {
    fn size(&self) -> Size {
        Size::new(self.width, self.height)
    }
}

impl DrawTarget for Canvas {
    type Color = Rgb888;
    type Error = Infallible;

    fn draw_iter<I: IntoIterator<Item = Pixel<Rgb888>>>(&mut self, pixels: I) -> Result<(), Infallible> {
        for Pixel(at, colour) in pixels {
            self.set(i64::from(at.x), i64::from(at.y), colour);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_far_off_the_canvas_are_left_out_and_the_rest_clipped() {
        let mut canvas = Canvas::new(40, 30, Rgb888::BLACK);
        canvas.line((-1e12, 5.0), (1e12, 5.0), Rgb888::WHITE, 1);
        canvas.disc((1e9, 1e9), 9, Rgb888::WHITE, None);
        assert!((0..40).all(|x| canvas.pixel(x, 5) == Some(Rgb888::BLACK)));
        canvas.line((-10.0, 5.0), (100.0, 5.0), Rgb888::WHITE, 1);
        assert!((0..40).all(|x| canvas.pixel(x, 5) == Some(Rgb888::WHITE)));
        assert_eq!(canvas.pixel(40, 5), None);
    }

    #[test]
    fn a_canvas_encodes_as_a_png_of_its_size() {
        let mut canvas = Canvas::new(17, 9, Rgb888::new(10, 20, 30));
        canvas.set(3, 4, Rgb888::RED);
        let bytes = canvas.encode_png().unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info().unwrap();
        let mut rgb = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut rgb).unwrap();
        assert_eq!((info.width, info.height, info.color_type), (17, 9, png::ColorType::Rgb));
        assert_eq!(&rgb[3 * (4 * 17 + 3)..][..3], &[255, 0, 0]);
        assert_eq!(&rgb[..3], &[10, 20, 30]);
    }

    #[test]
    fn text_wraps_at_spaces_and_cuts_only_words_longer_than_a_line() {
        assert_eq!(wrap("the gap opens to 6.78 mm", 10), ["the gap", "opens to", "6.78 mm"]);
        assert_eq!(wrap("abcdefghijkl x", 5), ["abcde", "x"]);
        assert!(wrap("   ", 5).is_empty());
    }
}
