//! The lines of an OBJ file as obj-exporter writes them, encoded without
//! `core::fmt`: obj-exporter prints every coordinate with `{:.6}` and every
//! index with `{}`, one `write!` per number, and on a skinned scene's
//! frames that formatting was most of the OBJ encoding (`perf` on the scene
//! report's 100 x 100 skinned cloth at one thread: 28% of the run in
//! `obj::write`, of it the larger part in `core::fmt`'s exact float
//! formatting). The bytes are obj-exporter's: [`fixed6`] rounds as `{:.6}`
//! does, and the tests compare every kind of line with obj-exporter's text
//! (`super::obj` tests, and the golden frame hashes of the shipped scenes).

use std::io::Write;

use op_dynamics::Vec3;

/// Magnitudes below which [`fixed6`] encodes a number itself: `x · 10^6`
/// then has at most 50 bits before the point, and the exact product of a
/// double's 53-bit significand with `10^6` fits in 128 bits.
const LIMIT: f64 = 1e9;

/// Appends `x` as `format!("{x:.6}")` writes it: the exact decimal value
/// of the double rounded to six decimals, half to even; a `-` for every
/// value with its sign bit set (`-0.000000` for `-0.0` and for negatives
/// that round to zero). Magnitudes of [`LIMIT`] and more, infinities and
/// NaN go through `core::fmt`.
pub(super) fn fixed6(out: &mut Vec<u8>, x: f64) {
    if encodable(x) {
        let mut line = Line::new();
        line.fixed6(x);
        out.extend_from_slice(line.as_bytes());
    } else {
        // Writing into a `Vec` cannot fail.
        let _ = write!(out, "{x:.6}");
    }
}

/// Whether [`Line::fixed6`] encodes `x` (finite, below [`LIMIT`]).
fn encodable(x: f64) -> bool {
    x.abs() < LIMIT
}

/// `a · 10^6` rounded to an integer, half to even, for `0 <= a <`
/// [`LIMIT`]: `a = m · 2^e` exactly, so `a · 10^6 = m · 10^6 / 2^-e`, an
/// integer division whose remainder decides the rounding.
fn micro_units(a: f64) -> u64 {
    let bits = a.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1 << 52) - 1);
    let (m, e) = match biased {
        0 => (fraction, -1074),
        _ => (fraction | (1 << 52), biased - 1075),
    };
    let scaled = u128::from(m) * 1_000_000;
    if e >= 0 {
        // Not reached below the limit (a >= 2^52 there); exact all the same.
        return (scaled << e) as u64;
    }
    let shift = e.unsigned_abs();
    if shift >= 128 {
        // scaled < 2^73: the value is below 2^-55, which rounds to 0.
        return 0;
    }
    let quotient = scaled >> shift;
    let remainder = scaled - (quotient << shift);
    let half = 1u128 << (shift - 1);
    let up = remainder > half || (remainder == half && quotient & 1 == 1);
    (quotient + u128::from(up)) as u64
}

/// One line of text, built on the stack and appended to the file's buffer
/// at once (one copy per line instead of one per number). The longest
/// line is an `f` line of three `a//a` of ten digits each (71 bytes).
struct Line {
    buf: [u8; 128],
    len: usize,
}

impl Line {
    fn new() -> Line {
        Line {
            buf: [0; 128],
            len: 0,
        }
    }

    fn as_bytes(&self) -> &[u8] {
        &self.buf[..self.len]
    }

    /// Empties the line for the next one (its buffer is reused).
    fn clear(&mut self) {
        self.len = 0;
    }

    fn byte(&mut self, b: u8) {
        self.buf[self.len] = b;
        self.len += 1;
    }

    /// `n` in decimal, as `{}` writes it.
    fn decimal(&mut self, n: u64) {
        let digits = n.checked_ilog10().unwrap_or(0) as usize + 1;
        digits_into(&mut self.buf[self.len..self.len + digits], n);
        self.len += digits;
    }

    /// `x` as `{:.6}` writes it, for an [`encodable`] `x`.
    fn fixed6(&mut self, x: f64) {
        if x.is_sign_negative() {
            self.byte(b'-');
        }
        let micro = micro_units(x.abs());
        self.decimal(micro / 1_000_000);
        self.byte(b'.');
        digits_into(&mut self.buf[self.len..self.len + 6], micro % 1_000_000);
        self.len += 6;
    }
}

/// The two-digit decimal strings `00` to `99`, one after the other.
const PAIRS: &[u8; 200] = b"\
    0001020304050607080910111213141516171819\
    2021222324252627282930313233343536373839\
    4041424344454647484950515253545556575859\
    6061626364656667686970717273747576777879\
    8081828384858687888990919293949596979899";

/// Writes the last `out.len()` decimal digits of `n` into `out`, zero
/// padded, two digits per division (the encoding's inner loop: one
/// division by 100 instead of two by 10 per pair of digits).
#[inline]
fn digits_into(out: &mut [u8], mut n: u64) {
    let mut end = out.len();
    while end >= 2 {
        let pair = (n % 100) as usize * 2;
        n /= 100;
        out[end - 2..end].copy_from_slice(&PAIRS[pair..pair + 2]);
        end -= 2;
    }
    if end == 1 {
        out[0] = b'0' + (n % 10) as u8;
    }
}

/// Appends a `v` or `vn` line (`prefix`) per point of `points`, each
/// converted to file axes by `to_file`: `prefix x y z`, six decimals.
pub(super) fn point_lines(
    out: &mut Vec<u8>,
    prefix: &[u8],
    points: &[Vec3],
    to_file: impl Fn(&Vec3) -> [f64; 3],
) {
    let mut line = Line::new();
    for p in points {
        let c = to_file(p);
        if c.iter().all(|&x| encodable(x)) {
            line.clear();
            for &b in prefix {
                line.byte(b);
            }
            for x in c {
                line.byte(b' ');
                line.fixed6(x);
            }
            line.byte(b'\n');
            out.extend_from_slice(line.as_bytes());
        } else {
            out.extend_from_slice(prefix);
            for x in c {
                out.push(b' ');
                fixed6(out, x);
            }
            out.push(b'\n');
        }
    }
}

/// Appends an `f a//a b//b c//c` line per triangle: vertex and normal of
/// the same one-based rank.
pub(super) fn triangle_lines(out: &mut Vec<u8>, triangles: &[[u32; 3]]) {
    let mut line = Line::new();
    for t in triangles {
        line.clear();
        line.byte(b'f');
        for &v in t {
            line.byte(b' ');
            // `a//a`: the digits encoded once, then copied.
            let from = line.len;
            line.decimal(u64::from(v) + 1);
            let to = line.len;
            line.byte(b'/');
            line.byte(b'/');
            line.buf.copy_within(from..to, line.len);
            line.len += to - from;
        }
        line.byte(b'\n');
        out.extend_from_slice(line.as_bytes());
    }
}

/// Appends an `l a b` line per segment (one-based; no normal index, which
/// is not valid on a line).
pub(super) fn segment_lines(out: &mut Vec<u8>, segments: &[[u32; 2]]) {
    let mut line = Line::new();
    for s in segments {
        line.clear();
        line.byte(b'l');
        for &v in s {
            line.byte(b' ');
            line.decimal(u64::from(v) + 1);
        }
        line.byte(b'\n');
        out.extend_from_slice(line.as_bytes());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn std_fixed6(x: f64) -> String {
        format!("{x:.6}")
    }

    fn ours(x: f64) -> String {
        let mut out = Vec::new();
        fixed6(&mut out, x);
        String::from_utf8(out).unwrap()
    }

    /// Exact ties round half to even, signs are kept on zeros, and the
    /// edges of the fast path agree with `{:.6}`, alone and in a line.
    #[test]
    fn special_values_print_as_core_fmt_does() {
        let tie = 1.0 / 128.0; // 0.0078125: a tie at the sixth decimal
        let cases = [
            0.0,
            -0.0,
            tie,
            -tie,
            3.0 * tie,
            1e-9,
            -1e-9,
            5e-7,
            1.5e-6,
            2.5e-6,
            9.5e-7,
            123456.0000005,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            5e-324,
            LIMIT,
            -LIMIT,
            LIMIT - 1e-6,
            f64::from_bits(LIMIT.to_bits() - 1),
            1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            999_999.999_999_5,
            0.999_999_5,
            0.999_999_499_999,
        ];
        for x in cases {
            assert_eq!(ours(x), std_fixed6(x), "{x:e}");
            let mut line = Vec::new();
            point_lines(&mut line, b"v", &[Vec3::new(x, 1.5, -x)], |p| {
                [p.x, p.y, p.z]
            });
            let expected = format!("v {x:.6} 1.500000 {:.6}\n", -x);
            assert_eq!(String::from_utf8(line).unwrap(), expected);
        }
        assert_eq!(ours(tie), "0.007812");
        assert_eq!(ours(-0.0), "-0.000000");
    }

    /// Random doubles of every magnitude a frame holds, and values a few
    /// ulps around exact ties at the sixth decimal, print as `{:.6}`.
    #[test]
    fn random_values_print_as_core_fmt_does() {
        // SplitMix64: a fixed stream, no dependency.
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        };
        for _ in 0..200_000 {
            let r = next();
            let unit = (r >> 11) as f64 / (1u64 << 53) as f64;
            let exponent = (next() % 40) as i32 - 20;
            let x = (unit - 0.5) * 2f64.powi(exponent);
            assert_eq!(ours(x), std_fixed6(x), "{x:e}");
            // Near a tie: k + 1/2 millionths, and its neighbours.
            let k = (next() % 2_000_000_000) as f64 - 1e9;
            let tie = (k + 0.5) / 1e6;
            for y in [
                tie,
                f64::from_bits(tie.to_bits() + 1),
                f64::from_bits(tie.to_bits() - 1),
            ] {
                assert_eq!(ours(y), std_fixed6(y), "{y:e}");
            }
        }
    }

    /// Thousands of lines, some through `core::fmt` (beyond the limit),
    /// come out in order.
    #[test]
    fn many_lines_keep_their_order() {
        let points: Vec<Vec3> = (0..5000)
            .map(|k| {
                let big = if k % 997 == 0 { 1e12 } else { 1.0 };
                Vec3::new(
                    k as f64 * 0.37 - 900.0,
                    big * (k as f64).sin(),
                    -1e-7 * k as f64,
                )
            })
            .collect();
        let mut out = Vec::new();
        point_lines(&mut out, b"vn", &points, |p| [p.x, p.y, p.z]);
        let expected: String = points
            .iter()
            .map(|p| format!("vn {:.6} {:.6} {:.6}\n", p.x, p.y, p.z))
            .collect();
        assert!(String::from_utf8(out).unwrap() == expected);
    }

    #[test]
    fn indices_are_one_based_decimals() {
        let mut out = Vec::new();
        triangle_lines(&mut out, &[[0, 9, u32::MAX - 1]]);
        segment_lines(&mut out, &[[99, 100]]);
        assert_eq!(
            String::from_utf8(out).unwrap(),
            format!("f 1//1 10//10 {0}//{0}\nl 100 101\n", u32::MAX)
        );
    }

    /// Every digit count, odd and even (the digits go two at a time),
    /// and the numbers either side of each power of ten.
    #[test]
    fn indices_of_every_length_print_as_core_fmt_does() {
        let mut ranks = vec![0u32, u32::MAX - 1];
        for k in 1..10 {
            let p = 10u32.pow(k);
            ranks.extend([p - 2, p - 1, p, p + 7]);
        }
        let triangles: Vec<[u32; 3]> = ranks
            .chunks(3)
            .map(|c| [c[0], c[c.len() / 2], c[c.len() - 1]])
            .collect();
        let mut out = Vec::new();
        triangle_lines(&mut out, &triangles);
        let expected: String = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| u64::from(v) + 1);
                format!("f {a}//{a} {b}//{b} {c}//{c}\n")
            })
            .collect();
        assert_eq!(String::from_utf8(out).unwrap(), expected);
    }
}
