//! OBJ meshes and their MTL materials, read in parallel (`obj_fast`) or through tobj and placed
//! in the world. Owns reading the files, mapping MTL statements to scene materials (`Kd` →
//! diffuse, `illum` 3/5 → mirror tinted by `Ks`, `illum` 4/6/7 or `Ni` with `d` < 1 / `Tr` > 0
//! → glass), splitting faces by material, gathering a mesh light's faces into one mesh, and
//! dropping zero-area triangles. Errors inside an OBJ or MTL file name that file and its line;
//! errors about the file as a whole name the scene's `file` field. Must not call Embree.

use super::document::{Document, child_path};
use super::files::SceneFiles;
use super::obj_fast;
use super::rules::{has_zero_area, is_ior, is_unit_channel};
use super::validate::{MaterialTable, MeshPlacement};
use super::{Material, SceneError, TriangleMesh};
use glam::Vec3;
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::io::{BufRead, Read};
use std::path::{Path, PathBuf};

pub(crate) struct LoadedMesh {
    /// One mesh per material, in order of first use in the OBJ.
    pub meshes: Vec<TriangleMesh>,
    pub degenerate_triangles_dropped: usize,
    /// Material libraries that could not be read (an error only where faces need them).
    pub warnings: Vec<String>,
}

/// A material library that tobj read; its materials follow those of earlier libraries in
/// tobj's material list.
struct MtlLibrary {
    path: PathBuf,
    text: String,
    material_count: usize,
}

/// Reads the OBJ of the mesh object at `path` (a field path such as `objects[3]`).
pub(crate) fn load(
    doc: &Document,
    path: &str,
    scene_folder: &Path,
    placement: &MeshPlacement,
    materials: &mut MaterialTable,
    files: &dyn SceneFiles,
) -> Result<LoadedMesh, SceneError> {
    let file_field = child_path(path, "file");
    let obj = ObjFile::read(doc, &scene_folder.join(&placement.file), &file_field, files)?;
    let whole_file_error =
        |why: String| doc.error(&file_field, format!("`{}` {why}", obj.path.display()));

    // Scene material index for each tobj material id, filled on first use.
    let mut mapped: HashMap<usize, u32> = HashMap::new();
    let mut groups: Vec<MeshGroup> = Vec::new();
    let mut dropped = 0;
    for model in &obj.models {
        let material = match placement.material_override {
            Some(material) => material,
            None => obj.scene_material(doc, path, model, &mut mapped, materials)?,
        };
        let group = match groups.iter_mut().position(|g| g.mesh.material == material) {
            Some(i) => &mut groups[i],
            None => {
                groups.push(MeshGroup::new(material));
                groups.last_mut().expect("just pushed")
            }
        };
        dropped += group
            .append(&model.mesh, placement)
            .map_err(whole_file_error)?;
    }

    let meshes: Vec<TriangleMesh> = groups
        .into_iter()
        .map(|g| g.mesh)
        .filter(|m| !m.triangles.is_empty())
        .collect();
    if meshes.is_empty() {
        return Err(whole_file_error(if dropped > 0 {
            format!("has only zero-area triangles ({dropped})")
        } else {
            "has no faces".to_string()
        }));
    }
    let warnings = obj
        .library_failures
        .iter()
        .map(|failure| format!("{failure} (its materials are not available)"))
        .collect();
    Ok(LoadedMesh {
        meshes,
        degenerate_triangles_dropped: dropped,
        warnings,
    })
}

/// Reads the OBJ of the mesh light at `path` (`lights[2]`): every face, whatever its MTL
/// material, in one mesh with material 0 and no vertex normals (an emitter is flat-shaded).
pub(crate) fn load_emitter(
    doc: &Document,
    path: &str,
    scene_folder: &Path,
    placement: &MeshPlacement,
    files: &dyn SceneFiles,
) -> Result<(TriangleMesh, usize), SceneError> {
    let placement = MeshPlacement {
        file: placement.file.clone(),
        material_override: Some(0),
        keep_normals: false,
        ..*placement
    };
    let loaded = load(
        doc,
        path,
        scene_folder,
        &placement,
        &mut MaterialTable::default(),
        files,
    )?;
    let mesh = loaded.meshes.into_iter().next().expect("load gives a mesh");
    Ok((mesh, loaded.degenerate_triangles_dropped))
}

/// An OBJ as tobj read it, with the MTL libraries it named.
struct ObjFile {
    path: PathBuf,
    /// The scene field naming this file, for errors.
    file_field: String,
    models: Vec<tobj::Model>,
    /// All libraries' materials, in tobj's numbering.
    materials: Vec<tobj::Material>,
    libraries: Vec<MtlLibrary>,
    /// Libraries that could not be read or parsed; an error only where a face's material is
    /// in none of the libraries that could.
    library_failures: Vec<SceneError>,
}

impl ObjFile {
    fn read(
        doc: &Document,
        path: &Path,
        file_field: &str,
        files: &dyn SceneFiles,
    ) -> Result<ObjFile, SceneError> {
        let text = read_text(path, files)
            .map_err(|why| doc.error(file_field, format!("`{}` {why}", path.display())))?;

        let folder = path.parent().unwrap_or(Path::new("")).to_path_buf();
        let libraries = RefCell::new(Vec::<MtlLibrary>::new());
        let library_failures = RefCell::new(Vec::<SceneError>::new());
        let consumed = Cell::new(0);
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ignore_points: true,
            ignore_lines: true,
        };
        let load_library = |named: &Path| {
            // `mtllib a.mtl b.mtl` names two libraries (tobj hands over the whole rest of
            // the line); a single name with spaces is taken whole when that file exists.
            let whole = named.to_string_lossy().trim().to_string();
            let names: Vec<String> = if files.read(&folder.join(&whole)).is_ok() {
                vec![whole]
            } else {
                whole.split_whitespace().map(String::from).collect()
            };
            let mut all: Vec<tobj::Material> = Vec::new();
            // tobj's own map type, taken from the first library read.
            let mut by_name = None;
            for name in names {
                match read_library(&folder.join(&name), files) {
                    Ok((library, result)) => {
                        let Ok((materials, map)) = result else {
                            continue;
                        };
                        let names = by_name.get_or_insert_with(|| {
                            let mut empty = map.clone();
                            empty.clear();
                            empty
                        });
                        for m in materials {
                            names.entry(m.name.clone()).or_insert(all.len());
                            all.push(m);
                        }
                        libraries.borrow_mut().push(library);
                    }
                    Err(failure) => {
                        let failure = failure.unwrap_or_else(|why| {
                            // Unreadable: blame the `mtllib` statement being parsed.
                            located(path, line_of_byte(&text, consumed.get()), "", why)
                        });
                        library_failures.borrow_mut().push(SceneError {
                            field: file_field.to_string(),
                            ..failure
                        });
                    }
                }
            }
            match by_name {
                Some(names) => Ok((all, names)),
                None => Err(tobj::LoadError::OpenFileFailed),
            }
        };
        // The parallel reader where it can; tobj, after the checks it lacks, where not.
        let loaded = match obj_fast::load(&text, &consumed, load_library) {
            Some(loaded) => loaded,
            None => {
                check_obj_numbers(&text)
                    .map_err(|(line, why)| located(path, line, file_field, why))?;
                let mut reader = CountingReader::new(text.as_bytes(), &consumed);
                tobj::load_obj_buf(&mut reader, &options, load_library)
            }
        };
        let (models, materials) = loaded.map_err(|e| {
            let line = line_of_byte(&text, consumed.get());
            located(path, line, file_field, format!("OBJ error: {e}"))
        })?;
        Ok(ObjFile {
            path: path.to_path_buf(),
            file_field: file_field.to_string(),
            models,
            materials: materials.unwrap_or_default(),
            libraries: libraries.into_inner(),
            library_failures: library_failures.into_inner(),
        })
    }

    /// The scene material for `model`'s faces from its MTL material, mapped on first use.
    fn scene_material(
        &self,
        doc: &Document,
        object_path: &str,
        model: &tobj::Model,
        mapped: &mut HashMap<usize, u32>,
        table: &mut MaterialTable,
    ) -> Result<u32, SceneError> {
        let Some(id) = model
            .mesh
            .material_id
            .filter(|&id| id < self.materials.len())
        else {
            if let Some(failure) = self.library_failures.first() {
                return Err(failure.clone());
            }
            return Err(doc.error(
                &child_path(object_path, "material"),
                format!(
                    "faces of `{}` in `{}` have no MTL material; give the object a `material`",
                    model.name,
                    self.path.display()
                ),
            ));
        };
        if let Some(&index) = mapped.get(&id) {
            return Ok(index);
        }
        let (library, name) = library_of(&self.libraries, &self.materials, id);
        let material = map_mtl(&self.materials[id]).map_err(|(keyword, why)| {
            let line = mtl_line(&library.text, name, keyword);
            let message = format!("material `{name}`: {why}");
            located(&library.path, line, &self.file_field, message)
        })?;
        let index = table.add(material);
        mapped.insert(id, index);
        Ok(index)
    }
}

/// The faces of one material, gathered across OBJ groups.
struct MeshGroup {
    mesh: TriangleMesh,
    /// Whether its parts carry vertex normals, known once the first is in; all must agree.
    with_normals: Option<bool>,
}

impl MeshGroup {
    fn new(material: u32) -> MeshGroup {
        MeshGroup {
            mesh: TriangleMesh {
                material,
                ..Default::default()
            },
            with_normals: None,
        }
    }

    /// Appends a tobj mesh in world space; returns how many zero-area triangles it left out.
    fn append(&mut self, part: &tobj::Mesh, placement: &MeshPlacement) -> Result<usize, String> {
        let vertex_count = part.positions.len() / 3;
        let has_normals = placement.keep_normals && !part.normals.is_empty();
        if has_normals && part.normals.len() != part.positions.len() {
            return Err("some faces have vertex normals and others do not".into());
        }
        if *self.with_normals.get_or_insert(has_normals) != has_normals {
            return Err("faces of one material mix vertex normals with none".into());
        }

        let base = self.mesh.positions.len() as u32;
        let transform = &placement.transform;
        for p in part.positions.chunks_exact(3) {
            let world = transform.point(Vec3::new(p[0], p[1], p[2]));
            if !world.is_finite() {
                return Err("a transformed vertex is not finite (scale too large?)".into());
            }
            self.mesh.positions.push(world);
        }
        // OBJ `vt`: a part without them, among parts with them, gets (0, 0) at its vertices.
        let has_uvs = part.texcoords.len() == 2 * vertex_count && vertex_count > 0;
        if has_uvs && self.mesh.uvs.is_none() {
            self.mesh.uvs = Some(vec![glam::Vec2::ZERO; base as usize]);
        }
        if let Some(uvs) = &mut self.mesh.uvs {
            if has_uvs {
                let uv = part.texcoords.chunks_exact(2);
                uvs.extend(uv.map(|t| glam::Vec2::new(t[0], t[1])));
            } else {
                uvs.resize(uvs.len() + vertex_count, glam::Vec2::ZERO);
            }
        }
        if has_normals {
            let normals = self.mesh.normals.get_or_insert_with(Vec::new);
            for n in part.normals.chunks_exact(3) {
                normals.push(transform.normal(Vec3::new(n[0], n[1], n[2])));
            }
        }

        let mut dropped = 0;
        for corners in part.indices.chunks_exact(3) {
            if corners.iter().any(|&i| i as usize >= vertex_count) {
                return Err("a face index is out of range".into());
            }
            let triangle = [corners[0] + base, corners[1] + base, corners[2] + base];
            if has_zero_area(&self.mesh.positions, triangle) {
                dropped += 1;
            } else {
                self.mesh.triangles.push(triangle);
            }
        }
        Ok(dropped)
    }
}

/// Maps one MTL material; on failure gives the statement keyword to blame and why.
fn map_mtl(m: &tobj::Material) -> Result<Material, (&'static str, String)> {
    let glass = |ior: Option<f32>, because: &str| match ior {
        Some(ior) if is_ior(ior) => Ok(Material::clear_glass(ior)),
        Some(ior) => Err((
            "Ni",
            format!("Ni {ior} must be a finite index of refraction >= 1"),
        )),
        None => Err(("illum", format!("{because} means glass, which needs Ni"))),
    };
    match m.illumination_model {
        Some(3 | 5) => {
            let tint = m.specular.unwrap_or([1.0; 3]);
            if let Some(bad) = tint.iter().find(|&&x| !is_unit_channel(x)) {
                return Err(("Ks", format!("Ks channel {bad} is not in [0, 1]")));
            }
            return Ok(Material::Mirror {
                tint: Vec3::from_array(tint),
            });
        }
        Some(model @ (4 | 6 | 7)) => return glass(m.optical_density, &format!("illum {model}")),
        _ => {}
    }
    let transmittance = match m.unknown_param.get("Tr") {
        Some(text) => match text.trim().parse::<f32>() {
            Ok(tr) => tr,
            Err(_) => return Err(("Tr", format!("Tr `{text}` is not a number"))),
        },
        None => 0.0,
    };
    let see_through = m.dissolve.is_some_and(|d| d < 1.0) || transmittance > 0.0;
    if see_through && m.optical_density.is_some() {
        return glass(m.optical_density, "transparency");
    }
    let Some(kd) = m.diffuse else {
        return Err((
            "newmtl",
            "has no Kd (diffuse), illum 3/5 (mirror) or illum 4/6/7 with Ni (glass)".into(),
        ));
    };
    if let Some(bad) = kd.iter().find(|&&x| !is_unit_channel(x)) {
        return Err(("Kd", format!("Kd channel {bad} is not in [0, 1]")));
    }
    let kd = Vec3::from_array(kd);
    let number = |key: &'static str| -> Result<Option<f32>, (&'static str, String)> {
        match m.unknown_param.get(key) {
            None => Ok(None),
            Some(text) => match text.trim().parse::<f32>() {
                Ok(x) if (0.0..=1.0).contains(&x) => Ok(Some(x)),
                _ => Err((key, format!("{key} `{text}` is not a number in [0, 1]"))),
            },
        }
    };
    // The PBR extension: metallic `Pm` (a metal at 0.5 and above, of colour Kd), roughness
    // `Pr` (α = Pr², the usual convention).
    if let (Some(metallic), roughness) = (number("Pm")?, number("Pr")?) {
        let alpha = glam::Vec2::splat(roughness.unwrap_or(0.5).powi(2).max(1e-3));
        return Ok(Material::Bsdf(if metallic >= 0.5 {
            let r = kd.clamp(Vec3::ZERO, Vec3::splat(0.9999));
            crate::bsdf::Model::Conductor {
                eta: Vec3::ONE,
                k: 2.0 * r.powf(0.5) / (Vec3::ONE - r).powf(0.5),
                alpha,
            }
        } else {
            // A dielectric base: 4% at normal incidence, pbrt-v3 plastic's Fresnel.
            crate::bsdf::Model::Plastic {
                kd,
                ks: Vec3::ONE,
                alpha,
            }
        }));
    }
    // Phong's highlight (illum 2, Ks, exponent Ns) as plastic: α = √(2 / (Ns + 2)), the
    // microfacet lobe of the same width.
    let ks = Vec3::from_array(m.specular.unwrap_or([0.0; 3]));
    if m.illumination_model == Some(2) && ks.max_element() > 0.0 {
        if let Some(bad) = ks.to_array().iter().find(|&&x| !is_unit_channel(x)) {
            return Err(("Ks", format!("Ks channel {bad} is not in [0, 1]")));
        }
        let ns = m.shininess.unwrap_or(10.0).max(0.0);
        return Ok(Material::Bsdf(crate::bsdf::Model::Plastic {
            kd,
            ks,
            alpha: glam::Vec2::splat((2.0 / (ns + 2.0)).sqrt()),
        }));
    }
    Ok(Material::Diffuse { albedo: kd })
}

/// The library holding tobj material `id`, and the material's name.
fn library_of<'a>(
    libraries: &'a [MtlLibrary],
    materials: &'a [tobj::Material],
    id: usize,
) -> (&'a MtlLibrary, &'a str) {
    let mut first = 0;
    for library in libraries {
        if id < first + library.material_count {
            return (library, &materials[id].name);
        }
        first += library.material_count;
    }
    // tobj lists exactly the materials of the libraries it was given, so this is unreachable;
    // fall back to the last library rather than panic.
    (
        libraries.last().expect("a material implies a library"),
        &materials[id].name,
    )
}

/// Reads and parses one MTL file. On failure: `Ok(error)` located inside the MTL when it was
/// read but is malformed, `Err(why)` when it could not be read.
#[allow(clippy::type_complexity)]
fn read_library(
    path: &Path,
    files: &dyn SceneFiles,
) -> Result<(MtlLibrary, tobj::MTLLoadResult), Result<SceneError, String>> {
    let text = read_text(path, files)
        .map_err(|why| Err(format!("material library `{}` {why}", path.display())))?;
    if let Err((line, why)) = check_mtl_colours(&text) {
        return Err(Ok(located(path, line, "", why)));
    }
    let consumed = Cell::new(0);
    let result = tobj::load_mtl_buf(&mut CountingReader::new(text.as_bytes(), &consumed));
    match result {
        Ok((ref materials, _)) => {
            let material_count = materials.len();
            Ok((
                MtlLibrary {
                    path: path.to_path_buf(),
                    text,
                    material_count,
                },
                result,
            ))
        }
        Err(e) => {
            let line = line_of_byte(&text, consumed.get());
            Err(Ok(located(path, line, "", format!("MTL error: {e}"))))
        }
    }
}

/// The line of the statement `keyword` inside material `name`'s block (or of its `newmtl`).
fn mtl_line(text: &str, name: &str, keyword: &str) -> usize {
    let mut block_line = None;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        let mut words = trimmed.split_whitespace();
        match words.next() {
            Some("newmtl") => {
                if block_line.is_some() {
                    break;
                }
                if trimmed["newmtl".len()..].trim() == name {
                    block_line = Some(i + 1);
                }
            }
            Some(word) if word == keyword && block_line.is_some() => return i + 1,
            _ => {}
        }
    }
    block_line.unwrap_or(1)
}

/// Rejects non-finite vertex positions, normals and texture coordinates, and zero normals,
/// which tobj accepts.
fn check_obj_numbers(text: &str) -> Result<(), (usize, String)> {
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let what = match words.next() {
            Some("v") => "vertex position",
            Some("vn") => "vertex normal",
            Some("vt") => "texture coordinate",
            _ => continue,
        };
        // Unparsable numbers are left to tobj, which reports them.
        let numbers: Vec<f32> = words.take(3).filter_map(|w| w.parse().ok()).collect();
        if numbers.iter().any(|x| !x.is_finite()) {
            return Err((i + 1, format!("{what} `{}` is not finite", line.trim())));
        }
        if what == "vertex normal" && numbers.len() == 3 && numbers.iter().all(|&x| x == 0.0) {
            return Err((i + 1, "vertex normal has zero length".into()));
        }
    }
    Ok(())
}

/// Rejects colour statements with fewer than three numbers, on which tobj 4 panics (the MTL
/// format allows `Kd r` alone, meaning grey; tobj does not).
fn check_mtl_colours(text: &str) -> Result<(), (usize, String)> {
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let Some(keyword @ ("Ka" | "Kd" | "Ks" | "Ke")) = words.next() else {
            continue;
        };
        let count = words.count();
        if count < 3 {
            return Err((
                i + 1,
                format!("{keyword} needs three numbers (r g b), found {count}"),
            ));
        }
    }
    Ok(())
}

fn read_text(path: &Path, files: &dyn SceneFiles) -> Result<String, String> {
    if files.is_dir(path) {
        return Err("is a directory, not a file".into());
    }
    let bytes = files
        .read(path)
        .map_err(|e| format!("cannot be read: {e}"))?;
    String::from_utf8(bytes).map_err(|_| "is not UTF-8 text".into())
}

fn located(file: &Path, line: usize, field: &str, message: String) -> SceneError {
    SceneError {
        file: file.to_path_buf(),
        line: Some(line),
        column: None,
        field: field.to_string(),
        message,
    }
}

/// 1-based line of the last of the first `consumed` bytes (the line being parsed).
fn line_of_byte(text: &str, consumed: usize) -> usize {
    let end = consumed.saturating_sub(1).min(text.len());
    text.as_bytes()[..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// A reader over text that records how many bytes tobj has taken, to locate its errors.
struct CountingReader<'a> {
    rest: &'a [u8],
    consumed: &'a Cell<usize>,
}

impl<'a> CountingReader<'a> {
    fn new(text: &'a [u8], consumed: &'a Cell<usize>) -> Self {
        consumed.set(0);
        CountingReader {
            rest: text,
            consumed,
        }
    }
}

impl Read for CountingReader<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.rest.read(buf)?;
        self.consumed.set(self.consumed.get() + n);
        Ok(n)
    }
}

impl BufRead for CountingReader<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        Ok(self.rest)
    }

    fn consume(&mut self, amount: usize) {
        self.rest = &self.rest[amount..];
        self.consumed.set(self.consumed.get() + amount);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_of_byte_points_at_the_line_just_read() {
        let text = "a\nbb\nc";
        assert_eq!(line_of_byte(text, 0), 1);
        assert_eq!(line_of_byte(text, 2), 1); // "a\n" read
        assert_eq!(line_of_byte(text, 5), 2); // "bb\n" read
        assert_eq!(line_of_byte(text, 6), 3); // "c" read, no final newline
    }

    #[test]
    fn mtl_line_finds_the_statement_in_the_right_block() {
        let text = "newmtl a\nKd 1 1 1\n\nnewmtl b\nNs 3\nKd 2 0 0\nnewmtl c\nKd 0 0 0\n";
        assert_eq!(mtl_line(text, "b", "Kd"), 6);
        assert_eq!(mtl_line(text, "b", "Ni"), 4);
        assert_eq!(mtl_line(text, "a", "Kd"), 2);
    }

    #[test]
    fn short_mtl_colours_are_refused_before_tobj_sees_them() {
        assert!(check_mtl_colours("newmtl a\nKd 0.1 0.2 0.3\nKs 1 1 1 extra\n").is_ok());
        let (line, why) = check_mtl_colours("newmtl a\n# Kd\nKd 0.3 0.3\n").unwrap_err();
        assert_eq!(line, 3);
        assert!(why.contains("Kd needs three numbers"), "{why}");
        assert_eq!(check_mtl_colours("Ke\n").unwrap_err().0, 1);
    }

    #[test]
    fn zero_area_includes_repeated_and_collinear_corners() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::Y];
        assert!(has_zero_area(&p, [0, 1, 2]));
        assert!(has_zero_area(&p, [0, 0, 3]));
        assert!(!has_zero_area(&p, [0, 1, 3]));
    }
}
