//! The stored photon: 20 bytes (position 12, power 4 as shared-exponent RGB, incoming
//! direction 2 and surface normal 2 as 8-bit octahedral pairs). Owns the packing and nothing
//! else; it knows neither the kd-tree nor any estimate. A photon map keeps the position in its
//! kd-tree only and the other 8 bytes as [`PhotonAttributes`], so no byte is stored twice.

use glam::Vec3;

/// One photon hit on a diffuse surface.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct Photon {
    position: [u32; 3],
    power: [u8; 4],
    direction: [u8; 2],
    normal: [u8; 2],
}

impl Photon {
    /// `direction` is the direction of travel when the photon arrived (pointing into the surface);
    /// `normal` the surface normal on the side the photon arrived from.
    pub fn new(position: Vec3, power: Vec3, direction: Vec3, normal: Vec3) -> Self {
        Self::with_directions(position, power, EncodedDirections::new(direction, normal))
    }

    /// The photon with its direction and normal encoded already.
    #[inline]
    pub fn with_directions(position: Vec3, power: Vec3, directions: EncodedDirections) -> Self {
        Self {
            position: position.to_array().map(f32::to_bits),
            power: encode_rgbe(power),
            direction: directions.direction,
            normal: directions.normal,
        }
    }

    pub fn position(&self) -> Vec3 {
        Vec3::from_array(self.position.map(f32::from_bits))
    }

    /// Power (flux) in watts per colour channel.
    pub fn power(&self) -> Vec3 {
        decode_rgbe(self.power)
    }

    pub fn direction(&self) -> Vec3 {
        decode_octahedral(self.direction)
    }

    pub fn normal(&self) -> Vec3 {
        decode_octahedral(self.normal)
    }

    /// Everything but the position: what a photon map stores beside its kd-tree.
    pub fn attributes(&self) -> PhotonAttributes {
        PhotonAttributes {
            power: self.power,
            direction: self.direction,
            normal: self.normal,
        }
    }

    /// The photon at `position` with `attributes`, bit for bit as it was split.
    pub fn from_parts(position: Vec3, attributes: PhotonAttributes) -> Self {
        Self {
            position: position.to_array().map(f32::to_bits),
            power: attributes.power,
            direction: attributes.direction,
            normal: attributes.normal,
        }
    }

    /// The 20 stored bytes, field by field, little-endian (for photon map files).
    pub fn to_le_bytes(&self) -> [u8; 20] {
        let mut b = [0u8; 20];
        for (i, p) in self.position.iter().enumerate() {
            b[4 * i..4 * i + 4].copy_from_slice(&p.to_le_bytes());
        }
        b[12..16].copy_from_slice(&self.power);
        b[16..18].copy_from_slice(&self.direction);
        b[18..20].copy_from_slice(&self.normal);
        b
    }

    /// The inverse of [`Photon::to_le_bytes`]: the same photon, bit for bit.
    pub fn from_le_bytes(b: [u8; 20]) -> Self {
        let word = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        Self {
            position: [word(0), word(4), word(8)],
            power: [b[12], b[13], b[14], b[15]],
            direction: [b[16], b[17]],
            normal: [b[18], b[19]],
        }
    }
}

/// A photon's direction and normal as stored (4 bytes): the tracer encodes them where a path
/// stores its photon and the power later, once the number of paths it is divided by is known.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct EncodedDirections {
    direction: [u8; 2],
    normal: [u8; 2],
}

impl EncodedDirections {
    #[inline]
    pub fn new(direction: Vec3, normal: Vec3) -> Self {
        Self {
            direction: encode_octahedral(direction),
            normal: encode_octahedral(normal),
        }
    }
}

/// A photon without its position: 8 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct PhotonAttributes {
    power: [u8; 4],
    direction: [u8; 2],
    normal: [u8; 2],
}

impl PhotonAttributes {
    /// Power (flux) in watts per colour channel.
    #[inline]
    pub fn power(&self) -> Vec3 {
        decode_rgbe(self.power)
    }
    #[inline]
    pub fn direction(&self) -> Vec3 {
        decode_octahedral(self.direction)
    }
    #[inline]
    pub fn normal(&self) -> Vec3 {
        decode_octahedral(self.normal)
    }
    /// The encoded normal as one number: equal codes are equal normals, so a loop over photons
    /// on one surface can test a normal once.
    #[inline]
    pub fn normal_code(&self) -> u16 {
        u16::from_be_bytes(self.normal)
    }
}

/// Shared-exponent RGB (Ward's RGBE), rounded to nearest: the error of every channel is at most
/// 1/256 of the largest channel, and the range covers 1e-38..1e38 so extreme powers survive.
pub fn encode_rgbe(c: Vec3) -> [u8; 4] {
    let c = c.max(Vec3::ZERO);
    let m = c.max_element();
    if m.is_nan() || m <= 1e-38 || !m.is_finite() {
        return [0; 4];
    }
    // m = f * 2^e with f in [0.5, 1): e from the exponent bits (m is normal here), exact
    // where log2 rounds up just below a power of two, and without its cost in photon tracing.
    let mut e = ((m.to_bits() >> 23) & 0xff) as i32 - 126;
    let mut scale = f64::from_bits(((8 - e + 1023) as u64) << 52);
    if round_non_negative(m as f64 * scale) >= 256 {
        e += 1;
        scale *= 0.5;
    }
    let q = |x: f32| round_non_negative((x as f64) * scale).min(255) as u8;
    [q(c.x), q(c.y), q(c.z), (e + 128).clamp(0, 255) as u8]
}

#[inline]
pub fn decode_rgbe(p: [u8; 4]) -> Vec3 {
    if p[3] == 0 {
        return Vec3::ZERO;
    }
    // 2^(e − 136) from its bits (exact, and without the cost of powi in the estimates' loops).
    let f = f64::from_bits(((p[3] as i64 - 136 + 1023) as u64) << 52);
    Vec3::new(
        (p[0] as f64 * f) as f32,
        (p[1] as f64 * f) as f32,
        (p[2] as f64 * f) as f32,
    )
}

/// Octahedral unit-vector encoding in two bytes (about 1° of error).
#[inline]
pub fn encode_octahedral(v: Vec3) -> [u8; 2] {
    let v = v / (v.x.abs() + v.y.abs() + v.z.abs()).max(1e-30);
    // The lower half folds over the diagonals. Chosen by masks, not a branch: a stored
    // photon's direction points down or up at random, and the tracer encodes one per photon.
    let fold = v.z < 0.0;
    let x = select(fold, (1.0 - v.y.abs()) * sign(v.x), v.x);
    let y = select(fold, (1.0 - v.x.abs()) * sign(v.y), v.y);
    let q = |t: f32| round_non_negative(((t.clamp(-1.0, 1.0) * 0.5 + 0.5) * 254.0) as f64) as u8;
    [q(x), q(y)]
}

/// `x.round()` for `0 ≤ x < 2^31` held exactly by an f32 times a power of two, as all callers
/// pass: adding one half is then exact and the cast truncates, without a call to `round`
/// (which photon tracing paid for on every stored photon).
#[inline]
fn round_non_negative(x: f64) -> u32 {
    (x + 0.5) as u32
}

/// Decodes from a table of all 65,536 codes (768 KiB, built on first use): the estimates
/// decode a normal for every photon they gather, and a lookup is several times cheaper than
/// the arithmetic and the square root.
#[inline]
pub fn decode_octahedral(p: [u8; 2]) -> Vec3 {
    static TABLE: std::sync::LazyLock<Vec<Vec3>> = std::sync::LazyLock::new(|| {
        (0..=u16::MAX)
            .map(|code| decode_octahedral_exactly(code.to_be_bytes()))
            .collect()
    });
    TABLE[u16::from_be_bytes(p) as usize]
}

fn decode_octahedral_exactly(p: [u8; 2]) -> Vec3 {
    let x = p[0] as f32 / 254.0 * 2.0 - 1.0;
    let y = p[1] as f32 / 254.0 * 2.0 - 1.0;
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        ((1.0 - y.abs()) * sign(x), (1.0 - x.abs()) * sign(y))
    } else {
        (x, y)
    };
    Vec3::new(x, y, z).normalize()
}

#[inline(always)]
fn sign(t: f32) -> f32 {
    select(t >= 0.0, 1.0, -1.0)
}

/// `if take_a { a } else { b }` by bit masks, which the compiler keeps free of branches.
#[inline(always)]
fn select(take_a: bool, a: f32, b: f32) -> f32 {
    let mask = 0u32.wrapping_sub(u32::from(take_a));
    f32::from_bits((a.to_bits() & mask) | (b.to_bits() & !mask))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn record_is_twenty_bytes_and_attributes_eight() {
        assert_eq!(std::mem::size_of::<Photon>(), 20);
        assert_eq!(std::mem::size_of::<PhotonAttributes>(), 8);
        let p = Photon::new(
            Vec3::new(1.0, -2.0, 3.5),
            Vec3::new(0.5, 2.0, 7.0),
            Vec3::X,
            -Vec3::Y,
        );
        assert_eq!(Photon::from_parts(p.position(), p.attributes()), p);
        assert_eq!(p.attributes().power(), p.power());
        assert_eq!(p.attributes().normal(), p.normal());
    }

    #[test]
    fn rgbe_round_trip_is_within_half_a_step() {
        for &s in &[
            1e-30f32, 1e-20, 1e-6, 0.37, 1.0, 3.0, 255.9, 1e6, 1e20, 1e30,
        ] {
            let c = Vec3::new(s, 0.5 * s, 0.01 * s);
            let d = decode_rgbe(encode_rgbe(c));
            assert!((d.x - c.x).abs() <= c.x / 255.0, "{s}: {c} -> {d}");
            assert!((d.y - c.y).abs() <= c.x / 255.0, "{s}: {c} -> {d}");
        }
        assert_eq!(decode_rgbe(encode_rgbe(Vec3::ONE)), Vec3::ONE);
        // Just below and at powers of two, where a rounded log2 would pick the wrong exponent.
        for k in [-100i32, -3, 0, 1, 7, 90] {
            let p = 2f32.powi(k);
            for m in [
                p,
                f32::from_bits(p.to_bits() - 1),
                f32::from_bits(p.to_bits() + 1),
            ] {
                let d = decode_rgbe(encode_rgbe(Vec3::new(m, 0.3 * m, 0.0)));
                assert!((d.x - m).abs() <= m / 255.0 && (d.y - 0.3 * m).abs() <= m / 255.0);
                assert!(
                    encode_rgbe(Vec3::splat(m))[0] >= 128,
                    "{m}: mantissa kept high"
                );
            }
        }
        assert_eq!(decode_rgbe(encode_rgbe(Vec3::ZERO)), Vec3::ZERO);
        assert_eq!(decode_rgbe(encode_rgbe(Vec3::splat(f32::NAN))), Vec3::ZERO);
    }

    #[test]
    fn rounding_without_round_matches_round() {
        let mut s = 7u32;
        for i in 0..100_000u32 {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            let x = if i < 1024 {
                // Every half step exactly: the ties.
                i as f32 * 0.5
            } else {
                (s >> 8) as f32 / (1u32 << 24) as f32 * 300.0
            };
            assert_eq!(round_non_negative(x as f64), x.round() as u32, "{x}");
        }
    }

    #[test]
    fn octahedral_round_trip_is_within_two_degrees() {
        let mut s = 1u32;
        for _ in 0..5000 {
            let mut r = || {
                s = s.wrapping_mul(1664525).wrapping_add(1013904223);
                (s >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
            };
            let v = Vec3::new(r(), r(), r());
            if v.length() < 1e-3 {
                continue;
            }
            let v = v.normalize();
            let d = decode_octahedral(encode_octahedral(v));
            assert!(v.dot(d) > (2.0f32).to_radians().cos(), "{v} -> {d}");
        }
        assert_eq!(decode_octahedral(encode_octahedral(Vec3::Z)), Vec3::Z);
    }

    #[test]
    fn octahedral_folding_by_masks_matches_the_branching_rule() {
        // The fold written plainly, with the sign rule `t >= 0 → 1` (so −0 counts as positive).
        fn reference(v: Vec3) -> [u8; 2] {
            let v = v / (v.x.abs() + v.y.abs() + v.z.abs()).max(1e-30);
            let sign = |t: f32| if t >= 0.0 { 1.0 } else { -1.0 };
            let (mut x, mut y) = (v.x, v.y);
            if v.z < 0.0 {
                x = (1.0 - v.y.abs()) * sign(v.x);
                y = (1.0 - v.x.abs()) * sign(v.y);
            }
            let q = |t: f32| ((t.clamp(-1.0, 1.0) * 0.5 + 0.5) * 254.0).round() as u8;
            [q(x), q(y)]
        }
        let mut s = 7u32;
        let mut r = || {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            (s >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0
        };
        let edges = [0.0, -0.0, 1.0, -1.0, 0.5, -0.5];
        for &x in &edges {
            for &y in &edges {
                for &z in &edges {
                    let v = Vec3::new(x, y, z);
                    assert_eq!(encode_octahedral(v), reference(v), "{v:?}");
                }
            }
        }
        for _ in 0..100_000 {
            let v = Vec3::new(r(), r(), r());
            assert_eq!(encode_octahedral(v), reference(v), "{v:?}");
        }
    }
}
