//! A world-space triangle soup with everything colour sampling needs: the common input of the voxelizer.
//!
//! The glTF importer ([`crate::import`]) and an animated model's poses ([`crate::anim`]) produce it; so can
//! any code, from an indexed mesh ([`TriangleSoup::from_mesh`]) or triangle by triangle
//! ([`TriangleSoup::push_triangle`]).

use std::any::Any;
use std::sync::{Arc, OnceLock};

use rayon::prelude::*;

use crate::error::{Result, VoxelError};

/// How texture coordinates outside [0, 1] are mapped (glTF sampler wrap modes).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// Tile the texture (glTF default).
    #[default]
    Repeat,
    /// Tile the texture, mirroring every other tile.
    MirroredRepeat,
    /// Clamp to the edge texels.
    ClampToEdge,
}

impl Wrap {
    /// Maps a texel coordinate (any integer) into `0..size`.
    pub fn apply(self, texel: i64, size: u32) -> u32 {
        let n = i64::from(size.max(1));
        if (0..n).contains(&texel) {
            return texel as u32; // every mode keeps a texel inside the image (and skips the division)
        }
        let t = match self {
            Wrap::Repeat => texel.rem_euclid(n),
            Wrap::ClampToEdge => texel.clamp(0, n - 1),
            Wrap::MirroredRepeat => {
                let period = texel.rem_euclid(2 * n);
                if period < n { period } else { 2 * n - 1 - period }
            }
        };
        t as u32
    }
}

/// An RGBA8 image in sRGB encoding (as glTF base-colour textures are).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` texels, row-major from the top-left, RGBA8 sRGB.
    pub rgba: Vec<[u8; 4]>,
}

impl Texture {
    /// Makes a texture, checking that the texel count matches the size.
    pub fn new(width: u32, height: u32, rgba: Vec<[u8; 4]>) -> Result<Self> {
        if width == 0 || height == 0 || rgba.len() != width as usize * height as usize {
            return Err(VoxelError::Invalid(format!("texture of {width}x{height} with {} texels", rgba.len())));
        }
        Ok(Self { width, height, rgba })
    }

    /// The texel nearest to `uv` (glTF convention: v grows downwards), with the given wrap modes.
    pub fn sample_nearest(&self, uv: [f32; 2], wrap: [Wrap; 2]) -> [u8; 4] {
        let x = wrap[0].apply(floor_to_i64(uv[0] * self.width as f32), self.width);
        let y = wrap[1].apply(floor_to_i64(uv[1] * self.height as f32), self.height);
        self.rgba[y as usize * self.width as usize + x as usize]
    }
}

/// `x.floor() as i64` (saturating, NaN to 0) without a libm call: the cast truncates towards zero, exactly
/// (an f32 of magnitude 2²³ or more is a whole number), and a negative fraction steps down one.
#[inline]
fn floor_to_i64(x: f32) -> i64 {
    let whole = x as i64;
    if whole as f32 > x { whole.saturating_sub(1) } else { whole }
}

/// A base-colour texture bound to a material: the image plus its sampler's wrap modes.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureBinding {
    /// The decoded image, shared between materials.
    pub texture: Arc<Texture>,
    /// Wrap modes along u and v.
    pub wrap: [Wrap; 2],
}

/// The colour sources of one material: base colour factor (linear RGBA) and an optional texture.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// `baseColorFactor`, linear RGBA.
    pub base_color: [f32; 4],
    /// `baseColorTexture`, if any; the soup's UVs are already the texture's coordinate set.
    pub texture: Option<TextureBinding>,
}

impl Default for Material {
    fn default() -> Self {
        Self { base_color: [1.0; 4], texture: None }
    }
}

/// One part of the model: a glTF primitive instance (mesh primitive under one node).
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// Index into [`TriangleSoup::materials`].
    pub material: usize,
    /// A readable name (mesh name and primitive index) for messages and the UI.
    pub name: String,
}

/// One vertex: world-space position plus the attributes colour sampling reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// World-space position.
    pub position: [f32; 3],
    /// Texture coordinate of the material's base-colour texture set.
    pub uv: [f32; 2],
    /// Linear RGBA vertex colour (`COLOR_0`), white when absent.
    pub color: [f32; 4],
}

impl Vertex {
    /// A vertex with only a position (white, uv 0).
    pub fn at(position: [f32; 3]) -> Self {
        Self { position, uv: [0.0; 2], color: [1.0; 4] }
    }
}

/// Indexed vertices, their attributes in separate lists (as a glTF primitive holds them).
pub(crate) struct IndexedVertices<'a> {
    /// World-space positions.
    pub positions: &'a [[f32; 3]],
    /// Texture coordinates, if any (else 0).
    pub uvs: Option<&'a [[f32; 2]]>,
    /// Linear RGBA colours, if any (else white).
    pub colors: Option<&'a [[f32; 4]]>,
    /// The vertices the triangles use, ascending, when they do not use all (the triangles then index this
    /// list); `None`: they use every vertex.
    pub used: Option<&'a [u32]>,
}

/// World-space triangles grouped into parts, with their materials: indexed vertices (positions, colours and
/// texture coordinates in lists of their own, as a glTF primitive holds them) and three vertex indices a
/// triangle. Every vertex is a corner of some triangle.
///
/// Positions change only through [`TriangleSoup::positions_mut`] and the `push` methods, so that what the soup
/// keeps about them (its `PositionCache`: the winding fill's closed parts, found once for every grid) never
/// outlives them.
#[derive(Clone, Debug, Default)]
pub struct TriangleSoup {
    /// Materials referenced by parts.
    pub materials: Vec<Material>,
    /// Parts referenced by triangles.
    pub parts: Vec<Part>,
    /// World-space position of each vertex.
    positions: Vec<[f32; 3]>,
    /// Linear RGBA colour of each vertex.
    colors: Vec<[f32; 4]>,
    /// Texture coordinate of each vertex; empty while no vertex has one (all 0).
    uvs: Vec<[f32; 2]>,
    /// Three vertex indices a triangle.
    triangles: Vec<[u32; 3]>,
    /// The part of each triangle.
    pub triangle_parts: Vec<u32>,
    /// What a pass derived from the positions alone, found when first needed; emptied whenever they can change.
    position_cache: PositionCache,
}

/// One value derived from a soup's positions alone, kept by the soup for every later voxelization: the
/// winding fill's closed parts (`orient::soup_parts`), which the app's grid changes reuse. The soup only holds
/// it (the module that finds it owns its type, so this leaf type knows nothing of the passes); a clone shares
/// it, and the soup forgets it whenever its positions can change.
#[derive(Clone, Default)]
pub(crate) struct PositionCache(OnceLock<Arc<dyn Any + Send + Sync>>);

impl PositionCache {
    /// The value kept, if it is a `T`.
    pub(crate) fn get<T: Any>(&self) -> Option<&T> {
        self.0.get()?.downcast_ref()
    }

    /// The value kept, found with `find` if there is none yet. The cache holds one type, the part analysis: a
    /// value of another type is a bug.
    pub(crate) fn get_or_init<T: Any + Send + Sync>(&self, find: impl FnOnce() -> T) -> &T {
        self.0.get_or_init(|| Arc::new(find())).downcast_ref().expect("the position cache holds one type")
    }

    /// Forgets the value.
    fn clear(&mut self) {
        self.0.take();
    }
}

impl std::fmt::Debug for PositionCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(if self.0.get().is_some() { "PositionCache(kept)" } else { "PositionCache(empty)" })
    }
}

/// Appends `values` to `list` (all of them, or those at `used`), or `count` copies of `absent` without values.
fn extend_attribute<T: Copy>(list: &mut Vec<T>, values: Option<&[T]>, used: Option<&[u32]>, count: usize, absent: T) {
    match (values, used) {
        (Some(values), None) => list.extend_from_slice(values),
        (Some(values), Some(used)) => list.extend(used.iter().map(|&i| values[i as usize])),
        (None, _) => list.resize(list.len() + count, absent),
    }
}

impl TriangleSoup {
    /// Adds a material and returns its index.
    pub fn add_material(&mut self, material: Material) -> usize {
        self.materials.push(material);
        self.materials.len() - 1
    }

    /// Adds a part using material `material` and returns its index.
    pub fn add_part(&mut self, material: usize, name: impl Into<String>) -> u32 {
        self.parts.push(Part { material, name: name.into() });
        (self.parts.len() - 1) as u32
    }

    /// Adds a triangle of three new vertices to part `part`.
    pub fn push_triangle(&mut self, part: u32, corners: [Vertex; 3]) {
        self.position_cache.clear();
        let first = self.positions.len() as u32;
        let uvs = corners.map(|v| v.uv);
        if uvs != [[0.0; 2]; 3] || !self.uvs.is_empty() {
            self.uvs.resize(self.positions.len(), [0.0; 2]);
            self.uvs.extend(uvs);
        }
        self.positions.extend(corners.map(|v| v.position));
        self.colors.extend(corners.map(|v| v.color));
        self.triangles.push([first, first + 1, first + 2]);
        self.triangle_parts.push(part);
    }

    /// The number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The world-space position of every vertex.
    pub fn positions(&self) -> &[[f32; 3]] {
        &self.positions
    }

    /// The positions, to change (a new pose, an edited mesh): forgets what the soup knew about them.
    pub fn positions_mut(&mut self) -> &mut [[f32; 3]] {
        self.position_cache.clear();
        &mut self.positions
    }

    /// The linear RGBA colour of every vertex (white where the file has none).
    pub fn colors(&self) -> &[[f32; 4]] {
        &self.colors
    }

    /// The colours, to change.
    pub fn colors_mut(&mut self) -> &mut [[f32; 4]] {
        &mut self.colors
    }

    /// Vertex `i`.
    #[inline]
    pub fn vertex(&self, i: usize) -> Vertex {
        Vertex { position: self.positions[i], uv: self.uv(i), color: self.colors[i] }
    }

    /// Vertex `i`'s texture coordinate (0 when the soup has none).
    #[inline]
    pub fn uv(&self, i: usize) -> [f32; 2] {
        self.uvs.get(i).copied().unwrap_or_default()
    }

    /// Appends the texture coordinates of `count` new vertices (`values`, all or those at `used`; none: 0), before
    /// their positions: the list stays empty while no vertex has one.
    fn extend_uvs(&mut self, values: Option<&[[f32; 2]]>, used: Option<&[u32]>, count: usize) {
        if values.is_none() && self.uvs.is_empty() {
            return;
        }
        self.uvs.resize(self.positions.len(), [0.0; 2]);
        extend_attribute(&mut self.uvs, values, used, count, [0.0; 2]);
    }

    /// The three vertex indices of every triangle.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The three corners of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [Vertex; 3] {
        self.triangles[t].map(|i| self.vertex(i as usize))
    }

    /// The three corners' positions of triangle `t`.
    #[inline]
    pub fn triangle_positions(&self, t: usize) -> [[f32; 3]; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// The three corners' colours (linear `COLOR_0`) of triangle `t`.
    #[inline]
    pub fn triangle_colors(&self, t: usize) -> [[f32; 4]; 3] {
        self.triangles[t].map(|i| self.colors[i as usize])
    }

    /// Every triangle's corners in turn, three a triangle.
    pub fn corners(&self) -> impl ExactSizeIterator<Item = Vertex> + '_ {
        self.triangles.as_flattened().iter().map(|&i| self.vertex(i as usize))
    }

    /// What a pass derived from the soup's positions alone and keeps for the next voxelization.
    pub(crate) fn position_cache(&self) -> &PositionCache {
        &self.position_cache
    }

    /// Room for `triangles` more triangles.
    pub(crate) fn reserve_triangles(&mut self, triangles: usize) {
        self.triangles.reserve(triangles);
        self.triangle_parts.reserve(triangles);
    }

    /// Adds `vertices` (the used ones) and `triangles` (three indices into them each, checked in range by the
    /// caller) to part `part`: the attribute lists are copied in bulk, the indices offset in parallel.
    pub(crate) fn push_indexed_triangles(&mut self, part: u32, vertices: &IndexedVertices<'_>, triangles: &[[u32; 3]]) {
        self.position_cache.clear();
        let base = self.positions.len() as u32;
        let count = vertices.used.map_or(vertices.positions.len(), <[u32]>::len);
        self.extend_uvs(vertices.uvs, vertices.used, count);
        extend_attribute(&mut self.positions, Some(vertices.positions), vertices.used, count, [0.0; 3]);
        extend_attribute(&mut self.colors, vertices.colors, vertices.used, count, [1.0; 4]);
        if base == 0 {
            self.triangles.extend_from_slice(triangles);
        } else {
            self.triangles.extend(triangles.iter().map(|t| t.map(|i| base + i)));
        }
        self.triangle_parts.resize(self.triangle_parts.len() + triangles.len(), part);
    }

    /// Builds a single-part soup from an indexed mesh with one flat linear-RGBA colour.
    pub fn from_mesh(mesh: &crate::shapes::IndexedMesh, base_color: [f32; 4]) -> Self {
        let mut soup = Self::default();
        soup.add_mesh(mesh, base_color, "mesh");
        soup
    }

    /// Adds an indexed mesh as a new part with its own flat linear-RGBA material; returns the part. Its vertices
    /// that no triangle uses are left out.
    pub fn add_mesh(&mut self, mesh: &crate::shapes::IndexedMesh, base_color: [f32; 4], name: &str) -> u32 {
        let material = self.add_material(Material { base_color, texture: None });
        let part = self.add_part(material, name);
        let used = used_vertices(mesh.positions.len(), mesh.triangles.as_flattened());
        let vertices = IndexedVertices {
            positions: &mesh.positions,
            uvs: None,
            colors: None,
            used: used.as_ref().map(|(used, _)| &used[..]),
        };
        let triangles = used.as_ref().map_or(&mesh.triangles[..], |(_, corners)| corners.as_chunks().0);
        self.push_indexed_triangles(part, &vertices, triangles);
        part
    }

    /// The number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangle_parts.len()
    }

    /// The part of triangle `t` (`triangle_parts[t]`). A soup of one part answers 0 without reading the list
    /// ([`validate`](Self::validate) refuses any other value there): the colour pass asks for the part of a
    /// triangle a cell, and a big model's list is megabytes that it would otherwise read a cache line a cell.
    #[inline]
    pub fn part_of(&self, t: usize) -> u32 {
        if self.parts.len() == 1 { 0 } else { self.triangle_parts[t] }
    }

    /// The material of triangle `t`.
    pub fn material_of(&self, t: usize) -> &Material {
        &self.materials[self.parts[self.part_of(t) as usize].material]
    }

    /// Checks the soup is usable: non-empty, finite, consistent indices.
    pub fn validate(&self) -> Result<()> {
        if self.triangle_parts.is_empty() {
            return Err(VoxelError::Empty(String::new()));
        }
        let vertices = self.positions.len();
        if self.triangles.len() != self.triangle_parts.len()
            || self.colors.len() != vertices
            || !(self.uvs.is_empty() || self.uvs.len() == vertices)
        {
            return Err(VoxelError::Invalid("the triangle or vertex lists differ in length".into()));
        }
        // Each part's material and every vertex checked once, then each triangle's part: the triangles are
        // searched for the first unusable one only when something is wrong.
        let part_usable: Vec<bool> = self.parts.iter().map(|p| p.material < self.materials.len()).collect();
        // Whole chunks at a time, without stopping at the first bad value: the loops vectorize (the soup is
        // searched for the first bad triangle below only when there is one).
        let finite = |p: &[f32; 3]| p[0].is_finite() & p[1].is_finite() & p[2].is_finite();
        let all_finite =
            self.positions.par_chunks(CHECKED_PER_TASK).all(|chunk| chunk.iter().fold(true, |ok, p| ok & finite(p)));
        let part_ok = |part: u32| part_usable.get(part as usize) == Some(&true);
        // With every part usable, a triangle's part is usable when it is below the count: one maximum.
        let parts_ok = if part_usable.iter().all(|&usable| usable) {
            let most = self.triangle_parts.par_chunks(CHECKED_PER_TASK).map(|chunk| chunk.iter().copied().max()).max();
            most.flatten().is_none_or(|most| (most as usize) < self.parts.len())
        } else {
            self.triangle_parts.par_iter().with_min_len(CHECKED_PER_TASK).all(|&part| part_ok(part))
        };
        if all_finite && parts_ok {
            return Ok(());
        }
        let usable = |t: usize| {
            part_ok(self.triangle_parts[t]) && self.triangle_positions(t).as_flattened().iter().all(|c| c.is_finite())
        };
        let Some(t) =
            (0..self.triangle_count()).into_par_iter().with_min_len(CHECKED_PER_TASK).find_first(|&t| !usable(t))
        else {
            return Ok(());
        };
        let part = self.triangle_parts[t];
        match self.parts.get(part as usize) {
            None => Err(VoxelError::Invalid(format!("triangle {t} refers to missing part {part}"))),
            Some(p) if p.material >= self.materials.len() => {
                Err(VoxelError::Invalid(format!("part {} refers to a missing material", p.name)))
            }
            Some(p) => Err(VoxelError::NonFinite(p.name.clone())),
        }
    }

    /// The axis-aligned bounds (min, max) of all vertices (every one a corner); `None` when empty.
    pub fn bounds(&self) -> Option<([f32; 3], [f32; 3])> {
        let first = *self.positions.first()?;
        let grow = |(mut lo, mut hi): ([f32; 3], [f32; 3]), p: [f32; 3]| {
            for a in 0..3 {
                lo[a] = lo[a].min(p[a]);
                hi[a] = hi[a].max(p[a]);
            }
            (lo, hi)
        };
        // Min and max of finite values do not depend on the order: chunks in parallel, then their bounds.
        let chunks =
            self.positions.par_chunks(1 << 16).map(|chunk| chunk.iter().fold((first, first), |b, &p| grow(b, p)));
        Some(chunks.reduce(|| (first, first), |a, b| grow(grow(a, b.0), b.1)))
    }
}

/// Vertices or triangles per task of [`TriangleSoup::validate`]'s checks.
const CHECKED_PER_TASK: usize = 1 << 14;

/// The vertices of `count` that `corners` (indices below `count`) use, ascending, and the corners re-indexed
/// to that list; `None` when they use every vertex.
pub(crate) fn used_vertices(count: usize, corners: &[u32]) -> Option<(Vec<u32>, Vec<u32>)> {
    let mut used = vec![false; count];
    for &i in corners {
        used[i as usize] = true;
    }
    if used.iter().all(|&u| u) {
        return None;
    }
    let mut renumbered = vec![0u32; count];
    let mut list = Vec::new();
    for (i, _) in used.iter().enumerate().filter(|(_, u)| **u) {
        renumbered[i] = list.len() as u32;
        list.push(i as u32);
    }
    Some((list, corners.iter().map(|&i| renumbered[i as usize]).collect()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes_map_into_range() {
        assert_eq!(Wrap::Repeat.apply(-1, 4), 3);
        assert_eq!(Wrap::Repeat.apply(9, 4), 1);
        assert_eq!(Wrap::ClampToEdge.apply(-5, 4), 0);
        assert_eq!(Wrap::ClampToEdge.apply(9, 4), 3);
        assert_eq!(Wrap::MirroredRepeat.apply(4, 4), 3);
        assert_eq!(Wrap::MirroredRepeat.apply(5, 4), 2);
        assert_eq!(Wrap::MirroredRepeat.apply(-1, 4), 0);
        for mode in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::ClampToEdge] {
            assert_eq!((0..4).map(|t| mode.apply(t, 4)).collect::<Vec<_>>(), [0, 1, 2, 3], "{mode:?}");
            assert_eq!(mode.apply(0, 0), 0, "{mode:?}");
        }
    }

    #[test]
    fn nearest_sampling_picks_the_texel_under_uv() {
        let tex = Texture::new(2, 2, vec![[1, 0, 0, 255], [2, 0, 0, 255], [3, 0, 0, 255], [4, 0, 0, 255]]).unwrap();
        let w = [Wrap::Repeat; 2];
        assert_eq!(tex.sample_nearest([0.25, 0.25], w)[0], 1);
        assert_eq!(tex.sample_nearest([0.75, 0.25], w)[0], 2);
        assert_eq!(tex.sample_nearest([0.25, 0.75], w)[0], 3);
        assert_eq!(tex.sample_nearest([1.75, -0.25], w)[0], 4);
        assert_eq!(tex.sample_nearest([f32::NAN, 0.0], w)[0], 1);
    }

    #[test]
    fn floor_without_libm_matches_floor_everywhere() {
        let mut values = vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, f32::MIN, 0.0, -0.0, 1e-40];
        values.extend([2f32.powi(63), -2f32.powi(63), 2f32.powi(23) + 1.0, -(2f32.powi(24)) - 2.0]);
        let mut state = 99u32;
        for _ in 0..100_000 {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let x = f32::from_bits(state);
            values.extend([x, x.fract(), (state >> 8) as f32 / 4096.0 - 2048.0]);
        }
        for x in values {
            assert_eq!(floor_to_i64(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn validate_rejects_nan_and_empty() {
        let mut soup = TriangleSoup::default();
        assert!(matches!(soup.validate(), Err(VoxelError::Empty(_))));
        let m = soup.add_material(Material::default());
        let p = soup.add_part(m, "bad");
        soup.push_triangle(p, [Vertex::at([0.0; 3]), Vertex::at([1.0, 0.0, f32::NAN]), Vertex::at([0.0, 1.0, 0.0])]);
        let err = soup.validate().unwrap_err();
        assert!(err.to_string().contains("NaN"), "{err}");
    }

    #[test]
    fn validate_names_a_missing_part_or_material_and_a_corner_that_is_not_finite_in_any_chunk() {
        // More triangles than a task checks, the bad one in a later task.
        let mut soup = TriangleSoup::default();
        let material = soup.add_material(Material::default());
        let part = soup.add_part(material, "strip");
        for k in 0..3 * CHECKED_PER_TASK {
            let x = k as f32;
            soup.push_triangle(part, [[x, 0.0, 0.0], [x + 1.0, 0.0, 0.0], [x, 1.0, 0.0]].map(Vertex::at));
        }
        assert!(soup.validate().is_ok());
        let bad = 2 * CHECKED_PER_TASK + 17;
        soup.triangle_parts[bad] = 1;
        let err = soup.validate().unwrap_err().to_string();
        assert!(err.contains(&format!("triangle {bad} refers to missing part 1")), "{err}");
        // A second part whose material is missing: its triangles are named by the part.
        soup.parts.push(Part { material: 7, name: "lost".into() });
        let err = soup.validate().unwrap_err().to_string();
        assert!(err.contains("part lost refers to a missing material"), "{err}");
        soup.triangle_parts[bad] = 0;
        assert!(soup.validate().is_ok(), "the part without a material is used by no triangle");
        soup.positions[3 * bad + 1][2] = f32::INFINITY;
        assert!(matches!(soup.validate(), Err(VoxelError::NonFinite(name)) if name == "strip"));
    }

    #[test]
    fn each_triangle_has_its_parts_material_in_a_soup_of_one_part_or_several() {
        let corners = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]].map(Vertex::at);
        let mut soup = TriangleSoup::default();
        let red = soup.add_material(Material { base_color: [1.0, 0.0, 0.0, 1.0], texture: None });
        let only = soup.add_part(red, "only");
        (0..3).for_each(|_| soup.push_triangle(only, corners));
        assert_eq!((0..3).map(|t| soup.part_of(t)).collect::<Vec<_>>(), [0; 3]);
        assert_eq!(soup.material_of(2).base_color, [1.0, 0.0, 0.0, 1.0]);

        let blue = soup.add_material(Material { base_color: [0.0, 0.0, 1.0, 1.0], texture: None });
        let second = soup.add_part(blue, "second");
        soup.push_triangle(second, corners);
        soup.push_triangle(only, corners);
        assert_eq!((0..5).map(|t| soup.part_of(t)).collect::<Vec<_>>(), [0, 0, 0, 1, 0]);
        let colors: Vec<[f32; 4]> = (0..5).map(|t| soup.material_of(t).base_color).collect();
        assert_eq!(colors[3], [0.0, 0.0, 1.0, 1.0]);
        assert_eq!(colors[4], [1.0, 0.0, 0.0, 1.0]);
    }
}
