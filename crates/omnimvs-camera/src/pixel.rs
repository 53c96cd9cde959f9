/// A position in a fisheye image, in pixels, 0-based: `col` along the image
/// width (x), `row` along the height (y). The centre of the top-left pixel is
/// `(0, 0)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pixel {
    pub col: f64,
    pub row: f64,
}

impl Pixel {
    pub const fn new(col: f64, row: f64) -> Self {
        Self { col, row }
    }
}
