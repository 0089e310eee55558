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
    if x.is_nan() || x.abs() >= LIMIT {
        // Writing into a `Vec` cannot fail.
        let _ = write!(out, "{x:.6}");
        return;
    }
    if x.is_sign_negative() {
        out.push(b'-');
    }
    let micro = micro_units(x.abs());
    push_decimal(out, micro / 1_000_000);
    out.push(b'.');
    let frac = micro % 1_000_000;
    let mut digits = [b'0'; 6];
    let mut rest = frac;
    for d in digits.iter_mut().rev() {
        *d = b'0' + (rest % 10) as u8;
        rest /= 10;
    }
    out.extend_from_slice(&digits);
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

/// Appends `n` in decimal, as `{}` writes it.
fn push_decimal(out: &mut Vec<u8>, mut n: u64) {
    let mut digits = [0u8; 20];
    let mut k = digits.len();
    loop {
        k -= 1;
        digits[k] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    out.extend_from_slice(&digits[k..]);
}

/// Appends a `v` or `vn` line (`prefix`) per point of `points`, each
/// converted to file axes by `to_file`: `prefix x y z`, six decimals.
pub(super) fn point_lines(
    out: &mut Vec<u8>,
    prefix: &[u8],
    points: &[Vec3],
    to_file: impl Fn(&Vec3) -> [f64; 3],
) {
    for p in points {
        out.extend_from_slice(prefix);
        for c in to_file(p) {
            out.push(b' ');
            fixed6(out, c);
        }
        out.push(b'\n');
    }
}

/// Appends an `f a//a b//b c//c` line per triangle: vertex and normal of
/// the same one-based rank.
pub(super) fn triangle_lines(out: &mut Vec<u8>, triangles: &[[u32; 3]]) {
    for t in triangles {
        out.push(b'f');
        for &v in t {
            let v = u64::from(v) + 1;
            out.push(b' ');
            push_decimal(out, v);
            out.extend_from_slice(b"//");
            push_decimal(out, v);
        }
        out.push(b'\n');
    }
}

/// Appends an `l a b` line per segment (one-based; no normal index, which
/// is not valid on a line).
pub(super) fn segment_lines(out: &mut Vec<u8>, segments: &[[u32; 2]]) {
    for s in segments {
        out.push(b'l');
        for &v in s {
            out.push(b' ');
            push_decimal(out, u64::from(v) + 1);
        }
        out.push(b'\n');
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
    /// edges of the fast path agree with `{:.6}`.
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
}
