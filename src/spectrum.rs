//! Colour from spectra: Planck's law, the CIE 1931 2° colour matching functions, the
//! conversion of XYZ to linear sRGB (Rec. 709 primaries, D65 white), the white of a colour
//! temperature on the CIE daylight locus and the Bradford adaptation between two whites.
//! What pbrt's `blackbody` values and its film's white balance mean, as numbers. Pure
//! functions of wavelengths and temperatures; must not know scenes, files or images.

use glam::{DMat3, DVec3};

/// Wien's displacement constant b (m·K): Planck's law at T peaks at λ = b / T.
pub const WIEN_B: f64 = 2.897_772_1e-3;

/// The first wavelength of [`CIE_1931`], nm.
const FIRST_NM: f64 = 380.0;
/// The step between rows of [`CIE_1931`], nm.
const STEP_NM: f64 = 5.0;

/// CIE 1931 2° standard observer (x̄, ȳ, z̄) from 380 to 780 nm every 5 nm, as tabulated in
/// CIE 15:2004 (Colorimetry, 3rd edition), Table T.4.
const CIE_1931: [[f64; 3]; 81] = [
    [0.001368, 0.000039, 0.006450], // 380
    [0.002236, 0.000064, 0.010550], // 385
    [0.004243, 0.000120, 0.020050], // 390
    [0.007650, 0.000217, 0.036210], // 395
    [0.014310, 0.000396, 0.067850], // 400
    [0.023190, 0.000640, 0.110200], // 405
    [0.043510, 0.001210, 0.207400], // 410
    [0.077630, 0.002180, 0.371300], // 415
    [0.134380, 0.004000, 0.645600], // 420
    [0.214770, 0.007300, 1.039050], // 425
    [0.283900, 0.011600, 1.385600], // 430
    [0.328500, 0.016840, 1.622960], // 435
    [0.348280, 0.023000, 1.747060], // 440
    [0.348060, 0.029800, 1.782600], // 445
    [0.336200, 0.038000, 1.772110], // 450
    [0.318700, 0.048000, 1.744100], // 455
    [0.290800, 0.060000, 1.669200], // 460
    [0.251100, 0.073900, 1.528100], // 465
    [0.195360, 0.090980, 1.287640], // 470
    [0.142100, 0.112600, 1.041900], // 475
    [0.095640, 0.139020, 0.812950], // 480
    [0.057950, 0.169300, 0.616200], // 485
    [0.032010, 0.208020, 0.465180], // 490
    [0.014700, 0.258600, 0.353300], // 495
    [0.004900, 0.323000, 0.272000], // 500
    [0.002400, 0.407300, 0.212300], // 505
    [0.009300, 0.503000, 0.158200], // 510
    [0.029100, 0.608200, 0.111700], // 515
    [0.063270, 0.710000, 0.078250], // 520
    [0.109600, 0.793200, 0.057250], // 525
    [0.165500, 0.862000, 0.042160], // 530
    [0.225750, 0.914850, 0.029840], // 535
    [0.290400, 0.954000, 0.020300], // 540
    [0.359700, 0.980300, 0.013400], // 545
    [0.433450, 0.994950, 0.008750], // 550
    [0.512050, 1.000000, 0.005750], // 555
    [0.594500, 0.995000, 0.003900], // 560
    [0.678400, 0.978600, 0.002750], // 565
    [0.762100, 0.952000, 0.002100], // 570
    [0.842500, 0.915400, 0.001800], // 575
    [0.916300, 0.870000, 0.001650], // 580
    [0.978600, 0.816300, 0.001400], // 585
    [1.026300, 0.757000, 0.001100], // 590
    [1.056700, 0.694900, 0.001000], // 595
    [1.062200, 0.631000, 0.000800], // 600
    [1.045600, 0.566800, 0.000600], // 605
    [1.002600, 0.503000, 0.000340], // 610
    [0.938400, 0.441200, 0.000240], // 615
    [0.854450, 0.381000, 0.000190], // 620
    [0.751400, 0.321000, 0.000100], // 625
    [0.642400, 0.265000, 0.000050], // 630
    [0.541900, 0.217000, 0.000030], // 635
    [0.447900, 0.175000, 0.000020], // 640
    [0.360800, 0.138200, 0.000010], // 645
    [0.283500, 0.107000, 0.000000], // 650
    [0.218700, 0.081600, 0.000000], // 655
    [0.164900, 0.061000, 0.000000], // 660
    [0.121200, 0.044580, 0.000000], // 665
    [0.087400, 0.032000, 0.000000], // 670
    [0.063600, 0.023200, 0.000000], // 675
    [0.046770, 0.017000, 0.000000], // 680
    [0.032900, 0.011920, 0.000000], // 685
    [0.022700, 0.008210, 0.000000], // 690
    [0.015840, 0.005723, 0.000000], // 695
    [0.011359, 0.004102, 0.000000], // 700
    [0.008111, 0.002929, 0.000000], // 705
    [0.005790, 0.002091, 0.000000], // 710
    [0.004109, 0.001484, 0.000000], // 715
    [0.002899, 0.001047, 0.000000], // 720
    [0.002049, 0.000740, 0.000000], // 725
    [0.001440, 0.000520, 0.000000], // 730
    [0.001000, 0.000361, 0.000000], // 735
    [0.000690, 0.000249, 0.000000], // 740
    [0.000476, 0.000172, 0.000000], // 745
    [0.000332, 0.000120, 0.000000], // 750
    [0.000235, 0.000085, 0.000000], // 755
    [0.000166, 0.000060, 0.000000], // 760
    [0.000117, 0.000042, 0.000000], // 765
    [0.000083, 0.000030, 0.000000], // 770
    [0.000059, 0.000021, 0.000000], // 775
    [0.000042, 0.000015, 0.000000], // 780
];

/// XYZ to linear sRGB (IEC 61966-2-1: Rec. 709 primaries, D65 white).
pub const XYZ_TO_LINEAR_SRGB: DMat3 = DMat3::from_cols(
    DVec3::new(3.240_454_2, -0.969_266_0, 0.055_643_4),
    DVec3::new(-1.537_138_5, 1.876_010_8, -0.204_025_9),
    DVec3::new(-0.498_531_4, 0.041_556_0, 1.057_225_2),
);

/// The Bradford cone-response matrix (XYZ to its sharpened LMS), for white adaptation.
const BRADFORD: DMat3 = DMat3::from_cols(
    DVec3::new(0.8951, -0.7502, 0.0389),
    DVec3::new(0.2664, 1.7135, -0.0685),
    DVec3::new(-0.1614, 0.0367, 1.0296),
);

/// D65's chromaticity (x, y), the white of linear sRGB.
pub const D65_XY: [f64; 2] = [0.3127, 0.3290];

/// Planck's law: the spectral radiance of a black body at `kelvin`, at `lambda_nm`, in
/// W·sr⁻¹·m⁻³. Zero for a temperature or wavelength that is not positive.
pub fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    const C: f64 = 299_792_458.0; // m/s
    const H: f64 = 6.626_070_15e-34; // J·s
    const K_B: f64 = 1.380_649e-23; // J/K
    if lambda_nm <= 0.0 || kelvin <= 0.0 {
        return 0.0;
    }
    let l = lambda_nm * 1e-9;
    2.0 * H * C * C / (l.powi(5) * ((H * C / (l * K_B * kelvin)).exp_m1()))
}

/// Planck's law at `kelvin` divided by its value at its peak (Wien's λ = b / T): 1 at the
/// peak, as pbrt normalises a `blackbody` spectrum.
pub fn planck_peak_normalised(lambda_nm: f64, kelvin: f64) -> f64 {
    let peak = planck(WIEN_B / kelvin * 1e9, kelvin);
    if peak > 0.0 {
        planck(lambda_nm, kelvin) / peak
    } else {
        0.0
    }
}

/// ∫ȳ dλ over the table, nm: the Y of a spectrum of constant 1.
fn y_integral() -> f64 {
    CIE_1931.iter().map(|row| row[1]).sum::<f64>() * STEP_NM
}

/// XYZ of `spectrum` (a function of wavelength in nm) as Σ s·x̄ Δλ / ∫ȳ dλ, so a spectrum of
/// constant 1 has Y = 1 (pbrt's convention for emission).
pub fn spectrum_xyz(spectrum: impl Fn(f64) -> f64) -> DVec3 {
    let sum: DVec3 = (CIE_1931.iter().enumerate())
        .map(|(i, row)| DVec3::from_array(*row) * spectrum(FIRST_NM + STEP_NM * i as f64))
        .sum();
    sum * STEP_NM / y_integral()
}

/// XYZ of a black body at `kelvin`, its spectrum normalised to 1 at its peak.
pub fn blackbody_xyz(kelvin: f64) -> DVec3 {
    spectrum_xyz(|lambda| planck_peak_normalised(lambda, kelvin))
}

/// Linear sRGB of an XYZ colour.
pub fn xyz_to_linear_srgb(xyz: DVec3) -> DVec3 {
    XYZ_TO_LINEAR_SRGB * xyz
}

/// Chromaticity (x, y) of an XYZ colour; (0, 0) for black.
pub fn chromaticity(xyz: DVec3) -> [f64; 2] {
    let sum = xyz.x + xyz.y + xyz.z;
    if sum > 0.0 {
        [xyz.x / sum, xyz.y / sum]
    } else {
        [0.0, 0.0]
    }
}

/// The chromaticity of CIE daylight (the D illuminants) at correlated colour temperature
/// `kelvin`, by CIE 15's polynomial in 1/T (defined from 4000 to 25000 K; extrapolated
/// beyond). The temperature is first moved from the c2 = 1.4380e-2 m·K scale the D series
/// was named on to today's 1.4388e-2, so 6500 gives D65.
pub fn daylight_xy(kelvin: f64) -> [f64; 2] {
    let t = kelvin * 1.4388 / 1.4380;
    let x = if t <= 7000.0 {
        -4.6070e9 / t.powi(3) + 2.9678e6 / t.powi(2) + 0.09911e3 / t + 0.244063
    } else {
        -2.0064e9 / t.powi(3) + 1.9018e6 / t.powi(2) + 0.24748e3 / t + 0.237040
    };
    [x, -3.0 * x * x + 2.87 * x - 0.275]
}

/// XYZ of chromaticity (x, y) at Y = 1.
fn white_xyz([x, y]: [f64; 2]) -> DVec3 {
    DVec3::new(x / y, 1.0, (1.0 - x - y) / y)
}

/// The von Kries adaptation in Bradford's cone space that takes white `from` to white `to`,
/// acting on XYZ.
pub fn bradford_adaptation(from: [f64; 2], to: [f64; 2]) -> DMat3 {
    let (source, target) = (BRADFORD * white_xyz(from), BRADFORD * white_xyz(to));
    BRADFORD.inverse() * DMat3::from_diagonal(target / source) * BRADFORD
}

/// White balance of a linear sRGB image shot under daylight of `kelvin`: the matrix that
/// takes that white to D65 (pbrt-v4's film `whitebalance` for its default sensor).
pub fn white_balance_srgb(kelvin: f64) -> DMat3 {
    let adapt = bradford_adaptation(daylight_xy(kelvin), D65_XY);
    XYZ_TO_LINEAR_SRGB * adapt * XYZ_TO_LINEAR_SRGB.inverse()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 2], b: [f64; 2], tolerance: f64) -> bool {
        (a[0] - b[0]).abs() <= tolerance && (a[1] - b[1]).abs() <= tolerance
    }

    #[test]
    fn illuminant_a_is_a_black_body_at_2856_kelvin() {
        // CIE 15: illuminant A, x = 0.44757, y = 0.40745.
        let xy = chromaticity(blackbody_xyz(2856.0));
        assert!(close(xy, [0.44757, 0.40745], 1e-3), "{xy:?}");
    }

    #[test]
    fn the_planckian_locus_at_6504_kelvin() {
        let xy = chromaticity(blackbody_xyz(6504.0));
        assert!(close(xy, [0.3135, 0.3236], 1e-3), "{xy:?}");
    }

    #[test]
    fn the_peak_normalised_spectrum_is_one_at_wiens_peak_and_below_it_elsewhere() {
        for kelvin in [1000.0, 2856.0, 5500.0, 10000.0] {
            let peak_nm = WIEN_B / kelvin * 1e9;
            assert!((planck_peak_normalised(peak_nm, kelvin) - 1.0).abs() < 1e-12);
            for factor in [0.9, 0.99, 1.01, 1.1] {
                assert!(planck_peak_normalised(peak_nm * factor, kelvin) < 1.0);
            }
        }
    }

    #[test]
    fn a_constant_spectrum_of_one_has_unit_luminance_and_the_d65_white_is_white() {
        assert!((spectrum_xyz(|_| 1.0).y - 1.0).abs() < 1e-12);
        let white = xyz_to_linear_srgb(white_xyz(D65_XY));
        assert!((white - DVec3::ONE).abs().max_element() < 1e-3, "{white}");
    }

    #[test]
    fn planck_matches_a_value_worked_by_hand() {
        // 2hc²/λ⁵ / (exp(hc/λkT) − 1) at 500 nm, 5000 K: 1.2108e13 W·sr⁻¹·m⁻³.
        let b = planck(500.0, 5000.0);
        assert!((b / 1.2108e13 - 1.0).abs() < 1e-3, "{b}");
        assert_eq!(planck(500.0, 0.0), 0.0);
    }

    #[test]
    fn daylight_at_6500_is_d65_and_its_white_balance_is_the_identity() {
        assert!(
            close(daylight_xy(6500.0), D65_XY, 2e-4),
            "{:?}",
            daylight_xy(6500.0)
        );
        let m = white_balance_srgb(6500.0);
        assert!(
            (m - DMat3::IDENTITY)
                .to_cols_array()
                .iter()
                .all(|v| v.abs() < 2e-3),
            "{m}"
        );
    }

    #[test]
    fn white_balance_makes_the_given_daylight_white() {
        for kelvin in [3000.0, 4500.0, 9000.0] {
            let grey = xyz_to_linear_srgb(white_xyz(daylight_xy(kelvin)));
            let balanced = white_balance_srgb(kelvin) * grey;
            let ratio = balanced / balanced.y;
            assert!(
                (ratio - DVec3::ONE).abs().max_element() < 1e-3,
                "{kelvin}: {ratio}"
            );
        }
        // A warm light balanced for a warm white loses red against blue.
        let m = white_balance_srgb(3000.0);
        let warm = m * DVec3::ONE;
        assert!(warm.x < warm.z, "{warm}");
    }
}
