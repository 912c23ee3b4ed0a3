//! The parameters of pbrt's materials as dpm keeps them: what the scene readers build and
//! textures change ([`ModelParameter`], [`Model::set`]), before a hit turns them into lobes
//! ([`super::Bsdf::new`]). Data only.

use glam::{Vec2, Vec3};

/// A material's scattering, with its parameters as dpm keeps them (roughness as the
/// Trowbridge–Reitz α along the shading frame's x and y; colours linear RGB).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Model {
    /// pbrt-v3 `plastic`: Lambert `kd` plus Trowbridge–Reitz reflection `ks` with the Fresnel
    /// reflectance of a dielectric of index 1.5.
    Plastic { kd: Vec3, ks: Vec3, alpha: Vec2 },
    /// pbrt-v3 `uber`: `opacity` of (Lambert `kd` + microfacet `ks` with dielectric Fresnel of
    /// index `eta` + specular reflection `kr` and transmission `kt` with that Fresnel), and
    /// 1 − `opacity` passed straight through.
    Uber {
        kd: Vec3,
        ks: Vec3,
        kr: Vec3,
        kt: Vec3,
        alpha: Vec2,
        eta: f32,
        opacity: Vec3,
    },
    /// pbrt-v3 `substrate`: Ashikhmin–Shirley's Fresnel blend of a diffuse `kd` under a glossy
    /// `ks` (the normal-incidence reflectance).
    Substrate { kd: Vec3, ks: Vec3, alpha: Vec2 },
    /// pbrt-v3 `translucent`: Lambert reflection and transmission of `kd` and microfacet
    /// reflection and transmission of `ks` (dielectric Fresnel, index 1.5), what is reflected
    /// scaled by `reflect`, what is transmitted by `transmit`.
    Translucent {
        kd: Vec3,
        ks: Vec3,
        reflect: Vec3,
        transmit: Vec3,
        alpha: Vec2,
    },
    /// A conductor of complex index `eta` + i`k` (per RGB channel), rough by `alpha` (0: a
    /// perfect mirror with the conductor's Fresnel reflectance).
    Conductor { eta: Vec3, k: Vec3, alpha: Vec2 },
    /// A dielectric of index `eta` (inside over outside, the outside on the side the shading
    /// normal points to), rough by `alpha` (0: smooth), reflection scaled by `reflect_tint`,
    /// transmission by `transmit_tint`.
    Dielectric {
        eta: f32,
        alpha: Vec2,
        reflect_tint: Vec3,
        transmit_tint: Vec3,
    },
    /// pbrt-v4 `thindielectric`: a thin smooth slab of index `eta`, its internal reflections
    /// summed; what it transmits goes straight on.
    ThinDielectric { eta: f32 },
    /// pbrt-v4 `coateddiffuse`: a dielectric coat (index `eta`, roughness `alpha`) over a
    /// Lambert base of `reflectance`, a medium of `thickness`, `albedo` and
    /// Henyey–Greenstein `g` between them.
    CoatedDiffuse {
        reflectance: Vec3,
        alpha: Vec2,
        eta: f32,
        thickness: f32,
        albedo: Vec3,
        g: f32,
    },
    /// pbrt-v4 `coatedconductor`: a dielectric coat over a conductor.
    CoatedConductor {
        interface_alpha: Vec2,
        interface_eta: f32,
        thickness: f32,
        albedo: Vec3,
        g: f32,
        conductor_eta: Vec3,
        conductor_k: Vec3,
        conductor_alpha: Vec2,
    },
    /// pbrt-v4 `diffusetransmission`: Lambert reflection of `reflectance` and Lambert
    /// transmission of `transmittance`.
    DiffuseTransmission {
        reflectance: Vec3,
        transmittance: Vec3,
    },
}

impl Model {
    /// The model's diffuse colour (`Kd` / `reflectance`), for textures to set, if it has one.
    pub fn diffuse_mut(&mut self) -> Option<&mut Vec3> {
        match self {
            Model::Plastic { kd, .. }
            | Model::Uber { kd, .. }
            | Model::Substrate { kd, .. }
            | Model::Translucent { kd, .. } => Some(kd),
            Model::CoatedDiffuse { reflectance, .. }
            | Model::DiffuseTransmission { reflectance, .. } => Some(reflectance),
            Model::Conductor { .. }
            | Model::Dielectric { .. }
            | Model::ThinDielectric { .. }
            | Model::CoatedConductor { .. } => None,
        }
    }
}

/// A parameter of a [`Model`] that a texture may give, by its role (pbrt's names for each
/// material are in docs/scene-format.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ModelParameter {
    /// The diffuse colour: `Kd`, or `reflectance` of a coated diffuse or diffuse transmitter.
    Diffuse,
    /// The glossy colour `Ks`.
    Specular,
    /// The specular reflection colour `Kr` (uber; a rough dielectric's reflection tint).
    Reflection,
    /// The specular transmission colour `Kt` (uber; a rough dielectric's transmission tint).
    Transmission,
    /// uber's `opacity`.
    Opacity,
    /// translucent's `reflect`.
    Reflect,
    /// translucent's `transmit`, a diffuse transmitter's `transmittance`.
    Transmit,
    /// The index of refraction: uber's `index`, a dielectric's or coat's `eta`.
    Eta,
    /// A conductor's `eta` (per channel), the coated conductor's `conductor.eta`.
    ConductorEta,
    /// A conductor's `k`, the coated conductor's `conductor.k`.
    ConductorK,
    /// A conductor's normal-incidence `reflectance` (pbrt-v4: η = 1, k = 2√r/√(1 − r)).
    ConductorReflectance,
    /// The coat's `thickness`.
    Thickness,
    /// A roughness, turned into α as `remap` says, along `axes`; `conductor` picks the coated
    /// conductor's conductor (its other roughness is the interface's).
    Roughness {
        axes: Axes,
        remap: Remap,
        conductor: bool,
    },
}

/// Which of a roughness's axes a texture gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axes {
    /// Both (`roughness`).
    Both,
    /// The shading frame's x (`uroughness`).
    U,
    /// Its y (`vroughness`).
    V,
}

/// How a roughness becomes Trowbridge–Reitz α.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Remap {
    /// α is the roughness (`remaproughness` false).
    None,
    /// pbrt-v3's polynomial in ln r.
    PbrtV3,
    /// pbrt-v4's √r.
    PbrtV4,
}

impl Remap {
    pub fn alpha(self, roughness: f32) -> f32 {
        let r = roughness.max(0.0);
        match self {
            _ if r == 0.0 => 0.0,
            Remap::None => r,
            Remap::PbrtV3 => super::pbrt_v3_roughness_to_alpha(r),
            Remap::PbrtV4 => super::pbrt_v4_roughness_to_alpha(r),
        }
    }
}

impl Model {
    /// Sets `parameter` to `value` (a float texture's value in every channel), kept in range:
    /// colours in [0, 1], indices at least 1 (a conductor's η above 0), `k` and thickness at
    /// least 0. A parameter the model does not have is left alone (the readers never pair
    /// them).
    pub fn set(&mut self, parameter: ModelParameter, value: Vec3) {
        use ModelParameter as P;
        let colour = value.clamp(Vec3::ZERO, Vec3::ONE);
        let index = value.x.max(1.0);
        match (self, parameter) {
            (m, P::Diffuse) => {
                if let Some(kd) = m.diffuse_mut() {
                    *kd = colour;
                }
            }
            (
                Model::Plastic { ks, .. }
                | Model::Uber { ks, .. }
                | Model::Substrate { ks, .. }
                | Model::Translucent { ks, .. },
                P::Specular,
            ) => *ks = colour,
            (Model::Uber { kr, .. }, P::Reflection) => *kr = colour,
            (Model::Uber { kt, .. }, P::Transmission) => *kt = colour,
            (Model::Dielectric { reflect_tint, .. }, P::Reflection) => *reflect_tint = colour,
            (Model::Dielectric { transmit_tint, .. }, P::Transmission) => *transmit_tint = colour,
            (Model::Uber { opacity, .. }, P::Opacity) => *opacity = colour,
            (Model::Translucent { reflect, .. }, P::Reflect) => *reflect = colour,
            (Model::Translucent { transmit, .. }, P::Transmit) => *transmit = colour,
            (Model::DiffuseTransmission { transmittance, .. }, P::Transmit) => {
                *transmittance = colour
            }
            (
                Model::Uber { eta, .. }
                | Model::Dielectric { eta, .. }
                | Model::ThinDielectric { eta }
                | Model::CoatedDiffuse { eta, .. }
                | Model::CoatedConductor {
                    interface_eta: eta, ..
                },
                P::Eta,
            ) => *eta = index,
            (
                Model::Conductor { eta, .. }
                | Model::CoatedConductor {
                    conductor_eta: eta, ..
                },
                P::ConductorEta,
            ) => *eta = value.max(Vec3::splat(1e-3)),
            (
                Model::Conductor { k, .. } | Model::CoatedConductor { conductor_k: k, .. },
                P::ConductorK,
            ) => *k = value.max(Vec3::ZERO),
            (
                Model::Conductor { eta, k, .. }
                | Model::CoatedConductor {
                    conductor_eta: eta,
                    conductor_k: k,
                    ..
                },
                P::ConductorReflectance,
            ) => {
                let r = value.clamp(Vec3::ZERO, Vec3::splat(0.9999));
                *eta = Vec3::ONE;
                *k = 2.0 * r.powf(0.5) / (Vec3::ONE - r).powf(0.5);
            }
            (
                Model::CoatedDiffuse { thickness, .. } | Model::CoatedConductor { thickness, .. },
                P::Thickness,
            ) => *thickness = value.x.max(0.0),
            (
                m,
                P::Roughness {
                    axes,
                    remap,
                    conductor,
                },
            ) => {
                if let Some(alpha) = m.alpha_mut(conductor) {
                    let a = remap.alpha(value.x);
                    match axes {
                        Axes::Both => *alpha = Vec2::splat(a),
                        Axes::U => alpha.x = a,
                        Axes::V => alpha.y = a,
                    }
                }
            }
            _ => {}
        }
    }

    /// The model's Trowbridge–Reitz α (for a coated conductor, its conductor's when
    /// `conductor`, else its interface's), if it has one.
    fn alpha_mut(&mut self, conductor: bool) -> Option<&mut Vec2> {
        match self {
            Model::Plastic { alpha, .. }
            | Model::Uber { alpha, .. }
            | Model::Substrate { alpha, .. }
            | Model::Translucent { alpha, .. }
            | Model::Conductor { alpha, .. }
            | Model::Dielectric { alpha, .. }
            | Model::CoatedDiffuse { alpha, .. } => Some(alpha),
            Model::CoatedConductor {
                interface_alpha,
                conductor_alpha,
                ..
            } => Some(if conductor {
                conductor_alpha
            } else {
                interface_alpha
            }),
            Model::ThinDielectric { .. } | Model::DiffuseTransmission { .. } => None,
        }
    }
}

#[cfg(test)]
#[path = "model_tests.rs"]
mod tests;
