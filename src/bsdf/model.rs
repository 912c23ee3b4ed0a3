//! The parameters of pbrt's materials as dpm keeps them: what the scene readers build and
//! textures change, before a hit turns them into lobes ([`super::Bsdf::new`]). Data only.

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
