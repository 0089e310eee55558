//! A small deterministic software rasterizer with a depth buffer.
//!
//! Screen points are `[x, y, w]`: pixel coordinates (`y` down) and inverse view
//! depth `w = 1/z`, which is linear in screen space, so interpolating it across
//! a triangle is exact under perspective. Larger `w` is nearer. A pixel is
//! covered when its centre is inside the shape. Anti-aliasing is by drawing at a
//! multiple of the final size and averaging ([`Canvas::downsample`]).

use image::RgbImage;

/// Screen point: pixel `x`, pixel `y` (down), inverse depth `w`.
pub(crate) type ScreenPt = [f64; 3];

/// Colour and depth buffers.
#[derive(Clone, Debug)]
pub(crate) struct Canvas {
    width: usize,
    height: usize,
    color: Vec<[u8; 3]>,
    depth: Vec<f32>,
}

impl Canvas {
    /// A canvas filled with `background`, at infinite depth.
    pub(crate) fn new(width: usize, height: usize, background: [u8; 3]) -> Self {
        Canvas {
            width,
            height,
            color: vec![background; width * height],
            depth: vec![0.0; width * height],
        }
    }

    /// Width in pixels.
    pub(crate) fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub(crate) fn height(&self) -> usize {
        self.height
    }

    /// Colour of pixel `(x, y)`.
    #[cfg(test)]
    pub(crate) fn pixel(&self, x: usize, y: usize) -> [u8; 3] {
        self.color[y * self.width + x]
    }

    /// Writes `color` at pixel `i` if `w` passes the depth test. `bias` (relative,
    /// >= 0) lets lines win against the surfaces they lie on.
    #[inline]
    fn plot(&mut self, i: usize, w: f64, color: [u8; 3], bias: f64) {
        let w = w * (1.0 + bias);
        if w.is_finite() && (w as f32) > self.depth[i] {
            self.depth[i] = w as f32;
            self.color[i] = color;
        }
    }

    /// Pixel range `[lo, hi)` of the centres `c + 0.5` within `[min, max]`, clamped to `0..n`.
    fn span(min: f64, max: f64, n: usize) -> (usize, usize) {
        let lo = (min - 0.5).ceil().max(0.0);
        let hi = ((max - 0.5).floor() + 1.0).min(n as f64);
        if lo.is_nan() || hi.is_nan() || lo >= hi {
            return (0, 0);
        }
        (lo as usize, hi as usize)
    }

    /// Fills a triangle with a flat colour, depth-tested.
    pub(crate) fn triangle(
        &mut self,
        a: ScreenPt,
        b: ScreenPt,
        c: ScreenPt,
        color: [u8; 3],
        bias: f64,
    ) {
        let area = edge(a, b, c);
        if !area.is_finite() || area.abs() < 1e-12 {
            return;
        }
        let (x0, x1) = Self::span(
            a[0].min(b[0]).min(c[0]),
            a[0].max(b[0]).max(c[0]),
            self.width,
        );
        let (y0, y1) = Self::span(
            a[1].min(b[1]).min(c[1]),
            a[1].max(b[1]).max(c[1]),
            self.height,
        );
        let inv = 1.0 / area;
        for y in y0..y1 {
            let py = y as f64 + 0.5;
            for x in x0..x1 {
                let p = [x as f64 + 0.5, py, 0.0];
                let l0 = edge(b, c, p) * inv;
                let l1 = edge(c, a, p) * inv;
                let l2 = edge(a, b, p) * inv;
                if l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0 {
                    let w = l0 * a[2] + l1 * b[2] + l2 * c[2];
                    self.plot(y * self.width + x, w, color, bias);
                }
            }
        }
    }

    /// A line of `thickness` pixels with square caps, drawn as a screen-space quad
    /// whose depth follows the segment.
    pub(crate) fn line(
        &mut self,
        a: ScreenPt,
        b: ScreenPt,
        thickness: f64,
        color: [u8; 3],
        bias: f64,
    ) {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let len = (dx * dx + dy * dy).sqrt();
        let h = thickness.max(1.0) * 0.5;
        if !len.is_finite() {
            return;
        }
        if len < 1e-9 {
            self.disc(a, h, color, bias);
            return;
        }
        let (ux, uy) = (dx / len * h, dy / len * h);
        let (nx, ny) = (-uy, ux);
        let p0 = [a[0] - ux + nx, a[1] - uy + ny, a[2]];
        let p1 = [a[0] - ux - nx, a[1] - uy - ny, a[2]];
        let p2 = [b[0] + ux - nx, b[1] + uy - ny, b[2]];
        let p3 = [b[0] + ux + nx, b[1] + uy + ny, b[2]];
        self.triangle(p0, p1, p2, color, bias);
        self.triangle(p0, p2, p3, color, bias);
    }

    /// A filled screen-space disc of `radius` pixels at constant depth.
    pub(crate) fn disc(&mut self, center: ScreenPt, radius: f64, color: [u8; 3], bias: f64) {
        let r = radius.max(0.5);
        let (x0, x1) = Self::span(center[0] - r, center[0] + r, self.width);
        let (y0, y1) = Self::span(center[1] - r, center[1] + r, self.height);
        for y in y0..y1 {
            let dy = y as f64 + 0.5 - center[1];
            for x in x0..x1 {
                let dx = x as f64 + 0.5 - center[0];
                if dx * dx + dy * dy <= r * r {
                    self.plot(y * self.width + x, center[2], color, bias);
                }
            }
        }
    }

    /// Averages `factor x factor` blocks into an image of `width/factor x height/factor`.
    pub(crate) fn downsample(&self, factor: usize) -> RgbImage {
        let f = factor.max(1);
        let (w, h) = (self.width / f, self.height / f);
        let n = (f * f) as u32;
        RgbImage::from_fn(w as u32, h as u32, |x, y| {
            let mut sum = [0u32; 3];
            for sy in 0..f {
                let row = (y as usize * f + sy) * self.width;
                for sx in 0..f {
                    let c = self.color[row + x as usize * f + sx];
                    for k in 0..3 {
                        sum[k] += u32::from(c[k]);
                    }
                }
            }
            image::Rgb(sum.map(|s| ((s + n / 2) / n) as u8))
        })
    }
}

/// Twice the signed area of `(a, b, p)`.
#[inline]
fn edge(a: ScreenPt, b: ScreenPt, p: ScreenPt) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    const BG: [u8; 3] = [255, 255, 255];
    const RED: [u8; 3] = [255, 0, 0];
    const BLUE: [u8; 3] = [0, 0, 255];

    fn tri(w: f64, scale: f64) -> [ScreenPt; 3] {
        let (cx, cy) = (32.0, 32.0);
        [
            [cx - 20.0 * scale, cy + 15.0 * scale, w],
            [cx + 20.0 * scale, cy + 15.0 * scale, w],
            [cx, cy - 25.0 * scale, w],
        ]
    }

    #[test]
    fn near_triangle_wins_in_either_order() {
        // Near (w = 1/2) red, far (w = 1/10) blue; the blue one is bigger.
        let near = tri(0.5, 0.6);
        let far = tri(0.1, 1.0);
        for order in 0..2 {
            let mut c = Canvas::new(64, 64, BG);
            if order == 0 {
                c.triangle(near[0], near[1], near[2], RED, 0.0);
                c.triangle(far[0], far[2], far[1], BLUE, 0.0); // other winding too
            } else {
                c.triangle(far[0], far[1], far[2], BLUE, 0.0);
                c.triangle(near[0], near[1], near[2], RED, 0.0);
            }
            assert_eq!(c.pixel(32, 32), RED, "order {order}");
            // Outside the red one but inside the blue one.
            assert_eq!(c.pixel(32, 44), BLUE, "order {order}");
            assert_eq!(c.pixel(1, 1), BG);
        }
    }

    #[test]
    fn perspective_depth_is_interpolated() {
        // A triangle whose depth varies crosses a flat one: both show somewhere.
        let mut c = Canvas::new(64, 64, BG);
        c.triangle(
            [0.0, 0.0, 0.3],
            [64.0, 0.0, 0.3],
            [0.0, 64.0, 0.3],
            BLUE,
            0.0,
        );
        c.triangle(
            [0.0, 0.0, 0.1],
            [64.0, 0.0, 0.5],
            [0.0, 64.0, 0.1],
            RED,
            0.0,
        );
        assert_eq!(c.pixel(5, 5), BLUE);
        assert_eq!(c.pixel(55, 3), RED);
    }

    #[test]
    fn lines_and_discs_respect_depth_and_bounds() {
        let mut c = Canvas::new(32, 32, BG);
        c.triangle(
            [0.0, 0.0, 0.5],
            [32.0, 0.0, 0.5],
            [0.0, 32.0, 0.5],
            BLUE,
            0.0,
        );
        // Behind the triangle: hidden; with a bias on its plane: visible.
        c.line([2.0, 4.0, 0.4], [20.0, 4.0, 0.4], 2.0, RED, 0.0);
        assert_eq!(c.pixel(10, 4), BLUE);
        c.line([2.0, 4.0, 0.5], [20.0, 4.0, 0.5], 2.0, RED, 1e-3);
        assert_eq!(c.pixel(10, 4), RED);
        // Far off-screen shapes draw nothing and do not panic.
        c.line([-1e9, -1e9, 1.0], [-1e9 + 5.0, -1e9, 1.0], 3.0, RED, 0.0);
        c.disc([1e12, 5.0, 1.0], 4.0, RED, 0.0);
        c.disc([28.0, 28.0, 1.0], 3.0, RED, 0.0);
        assert_eq!(c.pixel(28, 28), RED);
        c.triangle(
            [f64::NAN, 0.0, 1.0],
            [1.0, 1.0, 1.0],
            [0.0, 5.0, 1.0],
            RED,
            0.0,
        );
    }

    #[test]
    fn downsample_averages() {
        let mut c = Canvas::new(4, 2, [0, 0, 0]);
        c.disc([1.0, 1.0, 1.0], 0.8, [200, 100, 40], 0.0);
        let img = c.downsample(2);
        assert_eq!(img.dimensions(), (2, 1));
        assert_eq!(img.get_pixel(0, 0).0, [200, 100, 40]);
        assert_eq!(img.get_pixel(1, 0).0, [0, 0, 0]);
    }
}
