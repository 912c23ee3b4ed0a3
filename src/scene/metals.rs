//! The metals dpm knows by name, as complex indices of refraction per linear-sRGB channel:
//! what the pbrt reader's named spectra (`metal-Cu-eta` …) and the TOML format's
//! `metal = "Cu"` give a rough conductor. Data only.

/// The complex index (η, k) per linear-sRGB channel of the same metals, for rough conductors:
/// their measured spectra reduced to RGB.
pub const NAMED_METAL_INDICES: &[(&str, [f32; 3], [f32; 3])] = &[
    (
        "Cu",
        [0.200_438, 0.924_033, 1.102_21],
        [3.912_95, 2.452_85, 2.142_19],
    ),
    (
        "Au",
        [0.143_119, 0.374_957, 1.442_48],
        [3.983_16, 2.385_72, 1.603_22],
    ),
    (
        "Ag",
        [0.155_265, 0.116_723, 0.138_342],
        [4.828_35, 3.122_25, 2.146_96],
    ),
    (
        "Al",
        [1.657_46, 0.880_369, 0.521_229],
        [9.223_87, 6.269_52, 4.837],
    ),
];

/// The (η, k) of the metal `name` (`Cu`, `Au`, `Ag`, `Al`).
pub fn named_metal(name: &str) -> Option<(glam::Vec3, glam::Vec3)> {
    (NAMED_METAL_INDICES.iter())
        .find(|(m, _, _)| *m == name)
        .map(|(_, eta, k)| (glam::Vec3::from_array(*eta), glam::Vec3::from_array(*k)))
}
