//! The FNV-1a hash of photon map files and films, and the scene fingerprint built on it: every
//! number photon tracing reads from a scene (lights, materials and their textures, shapes), bit for bit, so a map
//! or film of another scene is refused. Owns the hash and what the fingerprint covers; knows
//! nothing of the file formats that use them.

use crate::scene::{
    Curves, Light, Material, SceneDescription, Shape, SpotFalloff, Texture, TexturedParameter,
    TriangleMesh,
};
use glam::Vec3;

/// FNV-1a, 64 bit: the file checksum and the scene fingerprint.
#[derive(Clone, Copy, Debug)]
pub struct Fnv64(u64);

impl Default for Fnv64 {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv64 {
    pub fn update(&mut self, bytes: &[u8]) {
        let mut h = self.0;
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        self.0 = h;
    }
    pub fn finish(&self) -> u64 {
        self.0
    }
    fn u32(&mut self, x: u32) {
        self.update(&x.to_le_bytes());
    }
    fn u64(&mut self, x: u64) {
        self.update(&x.to_le_bytes());
    }
    fn f32(&mut self, x: f32) {
        self.u32(x.to_bits());
    }
    fn vec3(&mut self, v: Vec3) {
        v.to_array().into_iter().for_each(|x| self.f32(x));
    }
    fn mesh(&mut self, mesh: &TriangleMesh) {
        self.u32(mesh.material);
        self.u64(mesh.positions.len() as u64);
        mesh.positions.iter().for_each(|&p| self.vec3(p));
        match &mesh.normals {
            Some(normals) => {
                self.u32(1);
                normals.iter().for_each(|&n| self.vec3(n));
            }
            None => self.u32(0),
        }
        self.u64(mesh.triangles.len() as u64);
        mesh.triangles.iter().flatten().for_each(|&i| self.u32(i));
    }

    fn curves(&mut self, curves: &Curves) {
        self.u32(curves.material);
        self.u32(curves.kind as u32);
        self.u64(curves.points.len() as u64);
        curves.points.iter().for_each(|&p| self.vec3(p));
        curves.radii.iter().for_each(|&r| self.f32(r));
        match &curves.normals {
            Some(normals) => {
                self.u32(1);
                normals.iter().for_each(|&n| self.vec3(n));
            }
            None => self.u32(0),
        }
    }
}

/// A fingerprint of everything photon tracing reads from a scene: lights, materials and
/// shapes after loading (mesh files included, since their triangles are), bit for bit. The
/// camera is left out: a map stays valid for another view or resolution of the same scene.
pub fn scene_fingerprint(scene: &SceneDescription) -> u64 {
    let mut h = Fnv64::default();
    h.update(b"dpm photon scene v1");
    h.u64(scene.lights.len() as u64);
    for light in &scene.lights {
        match light {
            Light::Point { position, power } => {
                h.u32(0);
                h.vec3(*position);
                h.vec3(*power);
            }
            Light::Sphere {
                center,
                radius,
                power,
            } => {
                h.u32(1);
                h.vec3(*center);
                h.f32(*radius);
                h.vec3(*power);
            }
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                power,
            } => {
                h.u32(2);
                h.vec3(*corner);
                h.vec3(*edge_u);
                h.vec3(*edge_v);
                h.vec3(*power);
            }
            Light::Spot {
                position,
                direction,
                cone_angle_degrees,
                falloff_start_degrees,
                falloff,
                power,
            } => {
                h.u32(3);
                h.vec3(*position);
                h.vec3(*direction);
                h.f32(*cone_angle_degrees);
                h.f32(*falloff_start_degrees);
                h.u32(match falloff {
                    SpotFalloff::Smoothstep => 0,
                    SpotFalloff::Quartic => 1,
                });
                h.vec3(*power);
            }
            Light::Distant {
                direction,
                irradiance,
            } => {
                h.u32(4);
                h.vec3(*direction);
                h.vec3(*irradiance);
            }
            Light::Environment { radiance } => {
                h.u32(5);
                h.vec3(*radiance);
            }
            Light::EnvironmentMap(map) => {
                h.u32(7);
                h.u32(map.width);
                h.u32(map.height);
                h.u32(map.mapping as u32);
                map.light_to_world
                    .to_cols_array()
                    .iter()
                    .for_each(|&x| h.f32(x));
                map.texels.iter().for_each(|&t| h.vec3(t));
            }
            Light::Mesh {
                mesh,
                power,
                two_sided,
            } => {
                h.u32(6);
                h.mesh(mesh);
                h.vec3(*power);
                h.u32(u32::from(*two_sided));
            }
        }
    }
    h.u64(scene.materials.len() as u64);
    for material in &scene.materials {
        match material {
            Material::Diffuse { albedo } => {
                h.u32(0);
                h.vec3(*albedo);
            }
            Material::Mirror { tint } => {
                h.u32(1);
                h.vec3(*tint);
            }
            Material::Glass {
                ior,
                reflect_tint,
                transmit_tint,
            } => {
                h.u32(2);
                h.f32(*ior);
                h.vec3(*reflect_tint);
                h.vec3(*transmit_tint);
            }
            Material::Mix { materials, amount } => {
                h.u32(4);
                h.u32(materials[0]);
                h.u32(materials[1]);
                h.f32(*amount);
            }
            Material::Bsdf(model) => {
                h.u32(3);
                // Every parameter, exactly: `Debug` prints each f32 so that it reads back.
                format!("{model:?}")
                    .bytes()
                    .for_each(|b| h.u32(u32::from(b)));
            }
        }
    }
    shapes(&mut h, &scene.shapes);
    // Instanced scenes only: a scene without them hashes as it always has.
    if !scene.instances.is_empty() {
        h.u64(scene.prototypes.len() as u64);
        for prototype in &scene.prototypes {
            shapes(&mut h, &prototype.shapes);
        }
        h.u64(scene.instances.len() as u64);
        for instance in &scene.instances {
            h.u32(instance.prototype);
            instance
                .object_to_world
                .to_cols_array()
                .iter()
                .for_each(|&x| h.f32(x));
        }
    }
    // Only a textured scene hashes textures and texture coordinates, so an untextured
    // scene's fingerprint (and its saved maps) stays what it was before textures.
    if !scene.textured_materials.is_empty() {
        h.u64(scene.textured_materials.len() as u64);
        for textured in &scene.textured_materials {
            h.u32(textured.material);
            h.u64(textured.textures.len() as u64);
            for (parameter, texture) in &textured.textures {
                h.parameter(parameter);
                h.texture(texture);
            }
        }
        let placed = scene.prototypes.iter().flat_map(|p| &p.shapes);
        for shape in scene.shapes.iter().chain(placed) {
            if let Shape::Triangles(mesh) = shape {
                let uvs = mesh.uvs.as_deref().unwrap_or_default();
                h.u64(uvs.len() as u64);
                uvs.iter().for_each(|t| {
                    h.f32(t.x);
                    h.f32(t.y);
                });
            }
        }
    }
    // Likewise only a scene with cut-outs hashes them (and the texture coordinates they read).
    let placed = scene.prototypes.iter().flat_map(|p| &p.shapes);
    for (i, shape) in scene.shapes.iter().chain(placed).enumerate() {
        if let Shape::Triangles(mesh) = shape
            && let Some(cutout) = &mesh.cutout
        {
            h.u64(i as u64);
            h.texture(&cutout.alpha);
            match &cutout.shadow_alpha {
                Some(t) => h.texture(t),
                None => h.u32(u32::MAX),
            }
            let uvs = mesh.uvs.as_deref().unwrap_or_default();
            h.u64(uvs.len() as u64);
            uvs.iter().for_each(|t| h.vec3(t.extend(0.0)));
        }
    }
    h.finish()
}

fn shapes(h: &mut Fnv64, shapes: &[Shape]) {
    h.u64(shapes.len() as u64);
    for shape in shapes {
        match shape {
            Shape::Sphere {
                center,
                radius,
                material,
                to_object,
            } => {
                h.u32(0);
                h.vec3(*center);
                h.f32(*radius);
                h.u32(*material);
                // Only a turned sphere hashes its frame, so unturned ones keep their
                // fingerprints (and their photon files).
                if *to_object != glam::Mat3::IDENTITY {
                    to_object.to_cols_array().iter().for_each(|x| h.f32(*x));
                }
            }
            Shape::Triangles(mesh) => {
                h.u32(1);
                h.mesh(mesh);
            }
            Shape::Curves(curves) => {
                h.u32(2);
                h.curves(curves);
            }
        }
    }
}

impl Fnv64 {
    /// The parameters that textures gave before models had their own keep their numbers, so
    /// those scenes' fingerprints stay what they were.
    fn parameter(&mut self, parameter: &TexturedParameter) {
        match parameter {
            TexturedParameter::Albedo => self.u32(0),
            TexturedParameter::Tint => self.u32(1),
            TexturedParameter::ReflectTint => self.u32(2),
            TexturedParameter::TransmitTint => self.u32(3),
            TexturedParameter::Ior => self.u32(4),
            TexturedParameter::Model(p) => {
                self.u32(5);
                // Every field: `Debug` names the variant, its axes, remap and conductor flag.
                format!("{p:?}")
                    .bytes()
                    .for_each(|b| self.u32(u32::from(b)));
            }
            TexturedParameter::MixAmount => self.u32(6),
        }
    }

    fn texture(&mut self, texture: &Texture) {
        match texture {
            Texture::Constant(c) => {
                self.u32(0);
                self.vec3(*c);
            }
            Texture::Image {
                image,
                mapping,
                wrap,
                scale,
                invert,
            } => {
                self.u32(1);
                self.u64(image.width as u64);
                image.texels.iter().for_each(|&t| self.vec3(t));
                (mapping.scale.to_array().iter())
                    .chain(&mapping.delta.to_array())
                    .for_each(|&x| self.f32(x));
                self.u32(*wrap as u32);
                self.f32(*scale);
                self.u32(u32::from(*invert));
            }
            Texture::Checkerboard { mapping, even, odd } => {
                self.u32(2);
                (mapping.scale.to_array().iter())
                    .chain(&mapping.delta.to_array())
                    .for_each(|&x| self.f32(x));
                self.texture(even);
                self.texture(odd);
            }
            Texture::Scale(a, b) => {
                self.u32(3);
                self.texture(a);
                self.texture(b);
            }
            Texture::Mix {
                first,
                second,
                amount,
            } => {
                self.u32(4);
                self.texture(first);
                self.texture(second);
                self.texture(amount);
            }
        }
    }
}
