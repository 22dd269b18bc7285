//! Bounds-checked accessor reading for every component type glTF allows, including the normalized and
//! integer encodings of KHR_mesh_quantization and sparse accessors.

use std::borrow::Cow;

use gltf::accessor::{Accessor, DataType, Dimensions};
use gltf::buffer::View;

use super::buffers::Buffers;
use crate::error::{Result, VoxelError};

/// The most values an accessor without a buffer view (all zeros, or a sparse base) may have.
const MAX_ZEROS: usize = 1 << 26;

/// Number of components of an accessor element.
pub(crate) fn component_count(dims: Dimensions) -> usize {
    match dims {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 | Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

/// Reads one component of type `ty` at `bytes[0..]` as f64, normalizing integers when `normalized`.
fn read_component(bytes: &[u8], ty: DataType, normalized: bool) -> f64 {
    let raw = match ty {
        DataType::I8 => f64::from(bytes[0] as i8),
        DataType::U8 => f64::from(bytes[0]),
        DataType::I16 => f64::from(i16::from_le_bytes([bytes[0], bytes[1]])),
        DataType::U16 => f64::from(u16::from_le_bytes([bytes[0], bytes[1]])),
        DataType::U32 => f64::from(u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
        DataType::F32 => return f64::from(f32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]])),
    };
    if normalized { normalize(raw, ty) } else { raw }
}

/// Maps an integer component of type `ty` to [0, 1] (unsigned) or [-1, 1] (signed), as glTF's `normalized`.
pub(crate) fn normalize(raw: f64, ty: DataType) -> f64 {
    match ty {
        DataType::I8 => (raw / 127.0).max(-1.0),
        DataType::U8 => raw / 255.0,
        DataType::I16 => (raw / 32767.0).max(-1.0),
        DataType::U16 => raw / 65535.0,
        DataType::U32 => raw / f64::from(u32::MAX),
        DataType::F32 => raw,
    }
}

/// The bytes of `count` elements of `elem` bytes in `view` from `offset` on (checked to be all there), and the
/// view's stride.
fn strided_bytes<'b>(
    view: &View<'_>,
    buffers: &'b Buffers<'_>,
    offset: usize,
    count: usize,
    elem: usize,
    what: &str,
) -> Result<(&'b [u8], usize)> {
    let bytes = buffers.view_bytes(view, what)?;
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(VoxelError::Invalid(format!("{what}: stride {stride} is smaller than an element ({elem})")));
    }
    if count == 0 {
        return Ok((&[], stride));
    }
    let end = (count - 1).checked_mul(stride).and_then(|s| s.checked_add(offset)).and_then(|s| s.checked_add(elem));
    match end.and_then(|end| bytes.get(offset..end)) {
        Some(elements) => Ok((elements, stride)),
        None => Err(VoxelError::Invalid(format!(
            "{what}: {count} elements of {elem} bytes do not fit in buffer view {} ({} bytes)",
            view.index(),
            bytes.len()
        ))),
    }
}

/// Reads `count` elements of `ncomp` components of type `ty` from `view` starting at `offset`.
#[allow(clippy::too_many_arguments)]
fn read_strided(
    view: &View<'_>,
    buffers: &Buffers<'_>,
    offset: usize,
    count: usize,
    ncomp: usize,
    ty: DataType,
    normalized: bool,
    what: &str,
) -> Result<Vec<f64>> {
    let (bytes, stride) = strided_bytes(view, buffers, offset, count, ncomp * ty.size(), what)?;
    let mut out = Vec::with_capacity(count * ncomp);
    for i in 0..count {
        let base = i * stride;
        for c in 0..ncomp {
            out.push(read_component(&bytes[base + c * ty.size()..], ty, normalized));
        }
    }
    Ok(out)
}

/// The elements of an accessor stored as plain little-endian values of `T` (`data_type` with `ncomp`
/// components, not normalized, not sparse, in a buffer view), in bulk: the view's bytes themselves when they
/// are packed and aligned (no copy), else one unaligned read an element. `None` for any other encoding (and
/// on big-endian targets): [`read_accessor`] reads those.
fn read_plain<'b, T: bytemuck::Pod>(
    accessor: &Accessor<'_>,
    buffers: &'b Buffers<'_>,
    data_type: DataType,
    ncomp: usize,
    what: &str,
) -> Result<Option<Cow<'b, [T]>>> {
    let plain = accessor.data_type() == data_type
        && component_count(accessor.dimensions()) == ncomp
        && !accessor.normalized()
        && accessor.sparse().is_none()
        && cfg!(target_endian = "little");
    let (Some(view), true) = (accessor.view(), plain) else { return Ok(None) };
    let size = std::mem::size_of::<T>();
    let count = accessor.count();
    let (bytes, stride) = strided_bytes(&view, buffers, accessor.offset(), count, size, what)?;
    if stride == size
        && let Ok(values) = bytemuck::try_cast_slice::<u8, T>(bytes)
    {
        return Ok(Some(Cow::Borrowed(values)));
    }
    let values = (0..count).map(|i| bytemuck::pod_read_unaligned(&bytes[i * stride..i * stride + size])).collect();
    Ok(Some(Cow::Owned(values)))
}

/// [`read_plain`] for `N` f32 components an element.
pub(crate) fn read_plain_f32<'b, const N: usize>(
    accessor: &Accessor<'_>,
    buffers: &'b Buffers<'_>,
    what: &str,
) -> Result<Option<Cow<'b, [[f32; N]]>>> {
    read_plain(accessor, buffers, DataType::F32, N, what)
}

/// Reads an accessor as a flat list of f64 components (`count * components` values), applying sparse
/// substitutions. Returns the values and the number of components per element.
pub(crate) fn read_accessor(accessor: &Accessor<'_>, buffers: &Buffers<'_>, what: &str) -> Result<(Vec<f64>, usize)> {
    let ncomp = component_count(accessor.dimensions());
    let ty = accessor.data_type();
    let count = accessor.count();
    let normalized = accessor.normalized();
    if count > 1 << 28 {
        return Err(VoxelError::Invalid(format!("{what}: accessor with {count} elements is too large")));
    }
    let mut values = match accessor.view() {
        Some(view) => read_strided(&view, buffers, accessor.offset(), count, ncomp, ty, normalized, what)?,
        // No data backs these zeros, so their number is bounded here rather than by the file's size.
        None if count * ncomp > MAX_ZEROS => {
            return Err(VoxelError::Invalid(format!(
                "{what}: accessor of {count} elements without a buffer view is too large"
            )));
        }
        None => vec![0.0; count * ncomp],
    };
    if let Some(sparse) = accessor.sparse() {
        let n = sparse.count();
        let idx_ty = match sparse.indices().index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let indices =
            read_strided(&sparse.indices().view(), buffers, sparse.indices().offset(), n, 1, idx_ty, false, what)?;
        let subst =
            read_strided(&sparse.values().view(), buffers, sparse.values().offset(), n, ncomp, ty, normalized, what)?;
        for (k, &index) in indices.iter().enumerate() {
            let i = index as usize;
            if i >= count {
                return Err(VoxelError::Invalid(format!("{what}: sparse index {i} out of range 0..{count}")));
            }
            values[i * ncomp..(i + 1) * ncomp].copy_from_slice(&subst[k * ncomp..(k + 1) * ncomp]);
        }
    }
    Ok((values, ncomp))
}

/// Reads an accessor of exactly `N` components per element (as f32).
pub(crate) fn read_vecs<const N: usize>(
    accessor: &Accessor<'_>,
    buffers: &Buffers<'_>,
    what: &str,
) -> Result<Vec<[f32; N]>> {
    if let Some(values) = read_plain_f32(accessor, buffers, what)? {
        return Ok(values.into_owned());
    }
    let (values, ncomp) = read_accessor(accessor, buffers, what)?;
    to_vecs(&values, ncomp, what)
}

/// Groups flat values of `ncomp` components per element into `N`-vectors (an error unless `ncomp == N`).
pub(crate) fn to_vecs<const N: usize>(values: &[f64], ncomp: usize, what: &str) -> Result<Vec<[f32; N]>> {
    if ncomp != N {
        return Err(VoxelError::Invalid(format!("{what}: expected {N} components per element, found {ncomp}")));
    }
    Ok(values.chunks_exact(N).map(|c| std::array::from_fn(|i| c[i] as f32)).collect())
}

/// Reads an index accessor (unsigned integers, one component): plain `u32` indices as they are in the buffer.
pub(crate) fn read_indices<'b>(
    accessor: &Accessor<'_>,
    buffers: &'b Buffers<'_>,
    what: &str,
) -> Result<Cow<'b, [u32]>> {
    if !matches!(accessor.data_type(), DataType::U8 | DataType::U16 | DataType::U32) || accessor.normalized() {
        return Err(VoxelError::Invalid(format!("{what}: indices must be unsigned integers")));
    }
    if let Some(indices) = read_plain::<u32>(accessor, buffers, DataType::U32, 1, what)? {
        return Ok(indices);
    }
    if let Some(indices) = read_plain::<u16>(accessor, buffers, DataType::U16, 1, what)? {
        return Ok(indices.iter().map(|&i| u32::from(i)).collect());
    }
    let (values, ncomp) = read_accessor(accessor, buffers, what)?;
    if ncomp != 1 {
        return Err(VoxelError::Invalid(format!("{what}: indices must be scalars")));
    }
    Ok(values.into_iter().map(|v| v as u32).collect())
}

/// Groups flat RGB or RGBA values into linear RGBA (alpha 1 for RGB).
pub(crate) fn to_colors(values: &[f64], ncomp: usize, what: &str) -> Result<Vec<[f32; 4]>> {
    match ncomp {
        3 => Ok(values.chunks_exact(3).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 1.0]).collect()),
        4 => Ok(values.chunks_exact(4).map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, c[3] as f32]).collect()),
        n => Err(VoxelError::Invalid(format!("{what}: colours need 3 or 4 components, found {n}"))),
    }
}
