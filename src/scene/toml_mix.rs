//! The TOML format's `mix` material: `materials = ["a", "b"]`, two names of `[materials]`
//! entries, and `amount`, the probability of the second (a number in [0, 1], default 0.5, or a
//! texture table whose channels' mean is read at each point), as a [`Material::Mix`]. Owns
//! those fields' checks and refusing mixes that reach themselves or nest deeper than
//! [`super::MAX_MIX_DEPTH`]; errors name the field. Must not evaluate textures.

use super::document::{Document, child_path};
use super::format::{AmountSpec, MaterialSpec, MixSpec};
use super::texture::channel_mean;
use super::toml_texture::{self, ImageSource};
use super::{Material, SceneError, Texture, TexturedParameter, rules};
use std::collections::HashMap;

/// The mix at `path`; `names` gives each `[materials]` entry's index.
pub(crate) fn mix(
    doc: &Document,
    path: &str,
    spec: &MixSpec,
    names: &HashMap<&str, u32>,
    images: &ImageSource,
) -> Result<(Material, Vec<(TexturedParameter, Texture)>), SceneError> {
    let field = |name: &str| child_path(path, name);
    let [first, second] = &spec.materials[..] else {
        return Err(doc.error(
            &field("materials"),
            format!(
                "a mix takes two material names, not {}",
                spec.materials.len()
            ),
        ));
    };
    let mut ids = [0; 2];
    for (k, name) in [first, second].into_iter().enumerate() {
        ids[k] = names.get(name.as_str()).copied().ok_or_else(|| {
            let mut known: Vec<&str> = names.keys().copied().collect();
            known.sort_unstable();
            doc.error(
                &format!("{}[{k}]", field("materials")),
                format!("unknown material `{name}` (defined: {})", known.join(", ")),
            )
        })?;
    }
    let (amount, textures) = match &spec.amount {
        None => (0.5, Vec::new()),
        Some(AmountSpec::Number(a)) if (0.0..=1.0).contains(a) => (*a, Vec::new()),
        Some(AmountSpec::Number(a)) => {
            return Err(doc.error(&field("amount"), format!("{a} is not in [0, 1]")));
        }
        Some(AmountSpec::Texture(table)) => {
            let texture = toml_texture::texture(doc, &field("amount"), table, images)?;
            let typical = channel_mean(texture.typical()).clamp(0.0, 1.0);
            (typical, vec![(TexturedParameter::MixAmount, texture)])
        }
    };
    Ok((
        Material::Mix {
            materials: ids,
            amount,
        },
        textures,
    ))
}

/// Refuses a mix that reaches itself or nests too deep, naming its `materials` field:
/// `materials` are the scene's, the first of them the `[materials]` entries `specs`, in order.
pub(crate) fn check_nesting(
    doc: &Document,
    specs: &[(String, MaterialSpec)],
    materials: &[Material],
) -> Result<(), SceneError> {
    match rules::mix_problem(materials) {
        None => Ok(()),
        Some((i, e)) => {
            let path = child_path("materials", &specs[i].0);
            Err(doc.error(&child_path(&path, "materials"), e.message))
        }
    }
}
