//! The default scene's triangle meshes, decoded primitive by primitive (accessors, Draco, materials) and placed
//! by their nodes' world transforms into a [`TriangleSoup`]: the static import, and the base the animated one
//! builds on (`animation`).

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

use glam::{DMat4, DVec3};
use gltf::mesh::Mode;
use rayon::prelude::*;

use super::accessor;
use super::buffers::Buffers;
use super::draco::DracoPrimitive;
use super::materials::MaterialCache;
use super::validate::{self, MAX_TRIANGLES};
use crate::error::{Result, VoxelError};
use crate::soup::{IndexedVertices, TriangleSoup, used_vertices};

/// The node, mesh and decoded primitive of one soup part, and its first soup vertex.
pub(super) struct PartSource {
    pub(super) node: usize,
    pub(super) mesh: usize,
    pub(super) decoded: usize,
    pub(super) first_vertex: usize,
}

/// Imports the soup, then hands the document and the builder (the soup and what it was decoded from) to
/// `finish`.
pub(super) fn import_with<T>(
    bytes: &[u8],
    base_dir: Option<&Path>,
    finish: impl FnOnce(&gltf::Document, SoupBuilder<'_>) -> Result<T>,
) -> Result<T> {
    let (document, blob) = validate::parse(bytes)?;
    let document = validate::check(document)?;
    let buffers = Buffers::load(&document, base_dir, blob)?;
    let mut builder = SoupBuilder {
        soup: TriangleSoup::default(),
        materials: MaterialCache::new(base_dir),
        document: &document,
        buffers: &buffers,
        parts_of_mesh: HashMap::new(),
        instances: Vec::new(),
    };
    let instances = scene_instances(&document)?;
    let primitives = instances.iter().filter_map(|(node, _)| node.mesh()).flat_map(|mesh| mesh.primitives());
    builder.materials.prefetch(primitives.filter(has_surface), &buffers);
    let mut triangles = 0usize;
    for mesh in instances.iter().filter_map(|(node, _)| node.mesh()) {
        triangles = triangles.saturating_add(builder.decode_mesh(&mesh)?);
    }
    builder.soup.reserve_triangles(triangles.min(MAX_TRIANGLES));
    for (node, transform) in instances {
        if let Some(mesh) = node.mesh() {
            builder.add_mesh(node.index(), &mesh, &transform)?;
        }
    }
    if builder.soup.triangle_count() == 0 {
        return Err(VoxelError::Empty(" (the default scene has no triangle meshes)".into()));
    }
    // No `TriangleSoup::validate` scan of every corner here: parts and materials are made consistent, and the
    // positions were checked finite where they were placed (`add_mesh`).
    finish(&document, builder)
}

/// Every mesh-carrying node instance of the default scene with its composed world transform.
fn scene_instances(document: &gltf::Document) -> Result<Vec<(gltf::Node<'_>, DMat4)>> {
    let roots: Vec<gltf::Node<'_>> = match document.default_scene().or_else(|| document.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            // No scene: take the nodes nobody lists as a child.
            let mut is_child = vec![false; document.nodes().len()];
            for n in document.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            document.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut out = Vec::new();
    // Depth-first with the ancestor chain, so a node that is its own ancestor is caught, not looped on.
    let mut stack: Vec<(gltf::Node<'_>, DMat4, Vec<usize>)> =
        roots.into_iter().rev().map(|n| (n, DMat4::IDENTITY, Vec::new())).collect();
    while let Some((node, parent, mut chain)) = stack.pop() {
        if chain.contains(&node.index()) {
            return Err(VoxelError::Invalid(format!(
                "node {} is its own ancestor (recursive node graph)",
                node.index()
            )));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if !world.is_finite() {
            return Err(VoxelError::NonFinite(format!("the transform of node {}", node.index())));
        }
        chain.push(node.index());
        if out.len() + stack.len() > MAX_TRIANGLES {
            return Err(VoxelError::Invalid("the node graph expands to too many instances".into()));
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world, chain.clone()));
        }
        if node.mesh().is_some() {
            out.push((node, world));
        }
    }
    Ok(out)
}

/// `positions` placed by `transform`, in f64 and rounded back to f32. The identity (most big files: one node)
/// only turns -0.0 into +0.0, as `c + 0.0` does: without a -0.0 the positions are borrowed as they are, bit
/// for bit what the f64 path gives.
fn world_positions<'p>(positions: &'p [[f32; 3]], transform: &DMat4) -> Cow<'p, [[f32; 3]]> {
    if *transform == DMat4::IDENTITY {
        let negative_zero = |c: &f32| c.to_bits() == (-0.0f32).to_bits();
        if !positions.as_flattened().iter().any(negative_zero) {
            return Cow::Borrowed(positions);
        }
        return Cow::Owned(positions.par_iter().map(|p| p.map(|c| c + 0.0)).collect());
    }
    let place = |p: &[f32; 3]| transform.transform_point3(DVec3::from(p.map(f64::from))).as_vec3().to_array();
    Cow::Owned(positions.par_iter().map(place).collect())
}

/// Whether `prim` draws triangles (points and lines have no surface to voxelize).
fn has_surface(prim: &gltf::Primitive<'_>) -> bool {
    !matches!(prim.mode(), Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip)
}

/// Expands primitive indices of `mode` into triangle corners, three a triangle (a triangle list's are its
/// indices, a trailing partial triangle left out).
fn triangles_of(mode: Mode, indices: Cow<'_, [u32]>) -> Cow<'_, [u32]> {
    let whole = indices.len() / 3 * 3;
    match mode {
        Mode::Triangles => match indices {
            Cow::Borrowed(indices) => Cow::Borrowed(&indices[..whole]),
            Cow::Owned(mut indices) => {
                indices.truncate(whole);
                Cow::Owned(indices)
            }
        },
        Mode::TriangleStrip => indices
            .windows(3)
            .enumerate()
            .flat_map(|(i, w)| if i % 2 == 0 { [w[0], w[1], w[2]] } else { [w[1], w[0], w[2]] })
            .collect(),
        Mode::TriangleFan => indices.windows(2).skip(1).flat_map(|w| [indices[0], w[0], w[1]]).collect(),
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip => Cow::Borrowed(&[]),
    }
}

pub(super) struct SoupBuilder<'a> {
    pub(super) soup: TriangleSoup,
    materials: MaterialCache,
    document: &'a gltf::Document,
    pub(super) buffers: &'a Buffers<'a>,
    /// Decoded primitives per mesh index, so a mesh used by several nodes is read once.
    pub(super) parts_of_mesh: HashMap<usize, Vec<DecodedPrimitive<'a>>>,
    /// Where each part came from.
    pub(super) instances: Vec<PartSource>,
}

/// One primitive's triangles in mesh space with their attributes (plain accessors borrowed from the buffers).
pub(super) struct DecodedPrimitive<'a> {
    /// The glTF primitive index within its mesh.
    pub(super) primitive: usize,
    material: usize,
    pub(super) name: String,
    pub(super) positions: Cow<'a, [[f32; 3]]>,
    uvs: Option<Vec<[f32; 2]>>,
    colors: Option<Cow<'a, [[f32; 4]]>>,
    /// The vertices the triangles use, ascending, when they do not use all; `None`: every vertex.
    pub(super) used: Option<Vec<u32>>,
    /// Three vertex indices a triangle (into `used` when there is such a list).
    corners: Cow<'a, [u32]>,
}

impl DecodedPrimitive<'_> {
    /// The triangles' vertex indices.
    fn triangles(&self) -> &[[u32; 3]] {
        self.corners.as_chunks().0
    }
}

impl<'a> SoupBuilder<'a> {
    /// Decodes the primitives of `mesh` unless done already (a mesh shared by several nodes is read once);
    /// returns its triangle count.
    fn decode_mesh(&mut self, mesh: &gltf::Mesh<'_>) -> Result<usize> {
        if !self.parts_of_mesh.contains_key(&mesh.index()) {
            let mut decoded = Vec::new();
            for prim in mesh.primitives() {
                if let Some(d) = self.decode_primitive(mesh, &prim)? {
                    decoded.push(d);
                }
            }
            self.parts_of_mesh.insert(mesh.index(), decoded);
        }
        Ok(self.parts_of_mesh[&mesh.index()].iter().map(|p| p.triangles().len()).sum())
    }

    fn add_mesh(&mut self, node: usize, mesh: &gltf::Mesh<'_>, transform: &DMat4) -> Result<()> {
        let added = self.decode_mesh(mesh)?;
        if self.soup.triangle_count() + added > MAX_TRIANGLES {
            return Err(VoxelError::Invalid(format!("the model has more than {MAX_TRIANGLES} triangles")));
        }
        for (decoded, prim) in self.parts_of_mesh[&mesh.index()].iter().enumerate() {
            let first_vertex = self.soup.vertex_count();
            self.instances.push(PartSource { node, mesh: mesh.index(), decoded, first_vertex });
            let part = self.soup.add_part(prim.material, prim.name.clone());
            let world = world_positions(&prim.positions, transform);
            // Placed positions can overflow (borrowed ones were checked when decoded).
            if matches!(world, Cow::Owned(_)) && world.as_flattened().iter().any(|c| !c.is_finite()) {
                return Err(VoxelError::NonFinite(prim.name.clone()));
            }
            let vertices = IndexedVertices {
                positions: &world,
                uvs: prim.uvs.as_deref(),
                colors: prim.colors.as_deref(),
                used: prim.used.as_deref(),
            };
            self.soup.push_indexed_triangles(part, &vertices, prim.triangles());
        }
        Ok(())
    }

    fn decode_primitive(
        &mut self,
        mesh: &gltf::Mesh<'_>,
        prim: &gltf::Primitive<'_>,
    ) -> Result<Option<DecodedPrimitive<'a>>> {
        let name = format!(
            "{} primitive {}",
            mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_owned),
            prim.index()
        );
        if !has_surface(prim) {
            return Ok(None);
        }
        let draco = DracoPrimitive::decode(prim, self.document, self.buffers, &name)?;
        let positions = match self.plain_attribute::<3>(prim, draco.as_ref(), &gltf::Semantic::Positions, &name)? {
            Some(positions) => positions,
            None => {
                let Some((values, ncomp)) = self.attribute(prim, draco.as_ref(), gltf::Semantic::Positions, &name)?
                else {
                    return Err(VoxelError::Invalid(format!("{name} has no POSITION attribute")));
                };
                Cow::Owned(accessor::to_vecs::<3>(&values, ncomp, &format!("{name} POSITION"))?)
            }
        };
        if positions.iter().flatten().any(|c| !c.is_finite()) {
            return Err(VoxelError::NonFinite(name));
        }
        let indices = match (&draco, prim.indices()) {
            (Some(draco), _) => Cow::Owned(draco.indices()),
            (None, Some(acc)) => accessor::read_indices(&acc, self.buffers, &format!("{name} indices"))?,
            (None, None) => (0..positions.len() as u32).collect(),
        };
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(VoxelError::Invalid(format!(
                "{name}: vertex index {bad} is out of range (the primitive has {} vertices)",
                positions.len()
            )));
        }
        let (soup_material, tex_coord) = self.materials.resolve(&mut self.soup, &prim.material(), self.buffers)?;
        let uvs = match tex_coord {
            Some(set) => {
                let semantic = gltf::Semantic::TexCoords(set.index);
                let raw = match self.plain_attribute::<2>(prim, draco.as_ref(), &semantic, &name)? {
                    Some(raw) => Some(raw.into_owned()),
                    None => match self.attribute(prim, draco.as_ref(), semantic, &name)? {
                        Some((values, ncomp)) => {
                            Some(accessor::to_vecs::<2>(&values, ncomp, &format!("{name} TEXCOORD_{}", set.index))?)
                        }
                        None => None,
                    },
                };
                if let Some(raw) = &raw {
                    check_len(&name, "TEXCOORD", raw.len(), positions.len())?;
                }
                raw.map(|raw| raw.into_iter().map(|uv| set.transform(uv)).collect())
            }
            None => None,
        };
        let colors = match self.colors(prim, draco.as_ref(), &name)? {
            Some(c) => {
                check_len(&name, "COLOR_0", c.len(), positions.len())?;
                Some(c)
            }
            None => None,
        };
        let corners = triangles_of(prim.mode(), indices);
        let (used, corners) = match used_vertices(positions.len(), &corners) {
            Some((used, renumbered)) => (Some(used), Cow::Owned(renumbered)),
            None => (None, corners),
        };
        Ok(Some(DecodedPrimitive {
            primitive: prim.index(),
            material: soup_material,
            name,
            positions,
            uvs,
            colors,
            used,
            corners,
        }))
    }

    /// The `N`-vectors of attribute `semantic` of an uncompressed `prim` when they are plain f32 in a buffer view
    /// (read in bulk); `None` for any other encoding, and when the primitive has no such attribute.
    fn plain_attribute<const N: usize>(
        &self,
        prim: &gltf::Primitive<'_>,
        draco: Option<&DracoPrimitive>,
        semantic: &gltf::Semantic,
        name: &str,
    ) -> Result<Option<Cow<'a, [[f32; N]]>>> {
        match (draco, prim.get(semantic)) {
            (None, Some(acc)) => {
                accessor::read_plain_f32(&acc, self.buffers, &format!("{name} {}", semantic.to_string()))
            }
            _ => Ok(None),
        }
    }

    /// The linear RGBA `COLOR_0` of `prim` (alpha 1 for RGB), if it has one.
    fn colors(
        &self,
        prim: &gltf::Primitive<'_>,
        draco: Option<&DracoPrimitive>,
        name: &str,
    ) -> Result<Option<Cow<'a, [[f32; 4]]>>> {
        let semantic = gltf::Semantic::Colors(0);
        if let Some(rgba) = self.plain_attribute::<4>(prim, draco, &semantic, name)? {
            return Ok(Some(rgba));
        }
        if let Some(rgb) = self.plain_attribute::<3>(prim, draco, &semantic, name)? {
            return Ok(Some(rgb.iter().map(|&[r, g, b]| [r, g, b, 1.0]).collect()));
        }
        match self.attribute(prim, draco, semantic, name)? {
            Some((values, ncomp)) => {
                accessor::to_colors(&values, ncomp, &format!("{name} COLOR_0")).map(|c| Some(Cow::Owned(c)))
            }
            None => Ok(None),
        }
    }

    /// The values of attribute `semantic` of `prim` (flat, with their component count): from its Draco stream
    /// when that carries it, else from its accessor; `None` when the primitive has no such attribute.
    fn attribute(
        &self,
        prim: &gltf::Primitive<'_>,
        draco: Option<&DracoPrimitive>,
        semantic: gltf::Semantic,
        name: &str,
    ) -> Result<Option<(Vec<f64>, usize)>> {
        let Some(acc) = prim.get(&semantic) else { return Ok(None) };
        let what = format!("{name} {}", semantic.to_string());
        if let Some(decoded) = draco.map(|d| d.attribute(&semantic.to_string(), &acc, &what)).transpose()?.flatten() {
            return Ok(Some(decoded));
        }
        accessor::read_accessor(&acc, self.buffers, &what).map(Some)
    }
}

pub(super) fn check_len(name: &str, what: &str, len: usize, expected: usize) -> Result<()> {
    if len == expected {
        Ok(())
    } else {
        Err(VoxelError::Invalid(format!("{name}: {what} has {len} elements but POSITION has {expected}")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_expand_to_triangles() {
        let corners = |mode, indices: &[u32]| triangles_of(mode, Cow::Borrowed(indices)).into_owned();
        assert_eq!(corners(Mode::TriangleStrip, &[0, 1, 2, 3]), [0, 1, 2, 2, 1, 3]);
        assert_eq!(corners(Mode::TriangleFan, &[0, 1, 2, 3]), [0, 1, 2, 0, 2, 3]);
        assert_eq!(corners(Mode::Triangles, &[0, 1, 2, 3]), [0, 1, 2]);
        assert_eq!(triangles_of(Mode::Triangles, Cow::Owned(vec![0, 1, 2, 3])).into_owned(), [0, 1, 2]);
        assert!(corners(Mode::Lines, &[0, 1, 2]).is_empty());
    }
}
