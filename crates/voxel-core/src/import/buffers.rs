//! The document's buffers, and the bytes of each buffer view: checked against their buffer, or decoded from
//! EXT_meshopt_compression (all modes and filters, via `meshoptimizer-rs`), whose fallback buffers are never
//! read. A GLB's binary chunk is borrowed from the file's bytes, not copied.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;
use std::sync::OnceLock;

use meshoptimizer_rs::codec::{Filter, Mode, decode_buffer_view};
use meshoptimizer_rs::{Limits, Workspace};
use serde::Deserialize;

use crate::error::{Result, VoxelError};

const MESHOPT: &str = "EXT_meshopt_compression";

/// The most bytes one meshopt buffer view may decode to (a guard against absurd counts in hostile files).
const MAX_DECODED_VIEW: usize = 1 << 29;

/// The buffers of a document and the decoded bytes of its meshopt-compressed views.
pub(crate) struct Buffers<'a> {
    /// Buffer contents by buffer index, padded to a multiple of 4 bytes (a meshopt fallback buffer is empty).
    data: Vec<Cow<'a, [u8]>>,
    /// Decoded bytes of compressed buffer views, by view index.
    decoded: HashMap<usize, Vec<u8>>,
    /// The buffers as the `gltf` crate's image decoder takes them (copies), made for the first image in a view.
    owned: OnceLock<Vec<gltf::buffer::Data>>,
}

/// The EXT_meshopt_compression object of a buffer view.
#[derive(Deserialize)]
#[serde(rename_all = "camelCase")]
struct MeshoptView {
    buffer: usize,
    #[serde(default)]
    byte_offset: usize,
    byte_length: usize,
    byte_stride: usize,
    count: usize,
    mode: String,
    #[serde(default = "no_filter")]
    filter: String,
}

fn no_filter() -> String {
    "NONE".into()
}

/// Whether `buffer` only stands in for meshopt-compressed data (EXT_meshopt_compression `fallback`).
fn is_meshopt_fallback(buffer: &gltf::Buffer<'_>) -> bool {
    buffer.extension_value(MESHOPT).and_then(|e| e.get("fallback")).and_then(|f| f.as_bool()) == Some(true)
}

/// `bytes` padded with zeros to a multiple of 4 bytes (as the `gltf` crate pads every buffer), borrowed when
/// they need none.
fn padded(bytes: Cow<'_, [u8]>) -> Cow<'_, [u8]> {
    if bytes.len().is_multiple_of(4) {
        return bytes;
    }
    let mut bytes = bytes.into_owned();
    bytes.resize(bytes.len().next_multiple_of(4), 0);
    Cow::Owned(bytes)
}

impl<'a> Buffers<'a> {
    /// Loads every buffer (the GLB's binary chunk `blob`, a data URI or a file next to `base_dir`), then decodes
    /// compressed views.
    pub fn load(document: &gltf::Document, base_dir: Option<&Path>, mut blob: Option<Cow<'a, [u8]>>) -> Result<Self> {
        let mut data = Vec::new();
        for buffer in document.buffers() {
            let what = format!("buffer {}", buffer.index());
            if is_meshopt_fallback(&buffer) {
                data.push(Cow::Borrowed(&[][..]));
                continue;
            }
            let source = buffer.source();
            let bytes = match matches!(source, gltf::buffer::Source::Bin).then(|| blob.take()).flatten() {
                Some(bin) => padded(bin),
                None => gltf::buffer::Data::from_source(source, base_dir)
                    .map(|data| Cow::Owned(data.0))
                    .map_err(|e| VoxelError::MissingData(format!("{what}: {e}")))?,
            };
            if bytes.len() < buffer.length() {
                return Err(VoxelError::MissingData(format!(
                    "{what}: {} bytes where the file declares {}",
                    bytes.len(),
                    buffer.length()
                )));
            }
            data.push(bytes);
        }
        let mut buffers = Self { data, decoded: HashMap::new(), owned: OnceLock::new() };
        let mut workspace = Workspace::new(Limits { max_bytes: MAX_DECODED_VIEW, ..Limits::default() });
        for view in document.views() {
            if let Some(ext) = view.extension_value(MESHOPT) {
                let decoded = buffers.decode_meshopt(&view, ext, &mut workspace)?;
                buffers.decoded.insert(view.index(), decoded);
            }
        }
        Ok(buffers)
    }

    /// Copies of the buffers, for the `gltf` crate's image decoder (made once, when first asked for).
    pub fn owned(&self) -> &[gltf::buffer::Data] {
        self.owned.get_or_init(|| self.data.iter().map(|bytes| gltf::buffer::Data(bytes.to_vec())).collect())
    }

    /// The bytes of `view`: decoded if compressed, else its range of its buffer (checked).
    pub fn view_bytes(&self, view: &gltf::buffer::View<'_>, what: &str) -> Result<&[u8]> {
        if let Some(decoded) = self.decoded.get(&view.index()) {
            return Ok(decoded);
        }
        self.buffer_range(
            view.buffer().index(),
            view.offset(),
            view.length(),
            &format!("{what}: buffer view {}", view.index()),
        )
    }

    /// `length` bytes at `offset` of buffer `index`, or an error naming `what` when they are not all there.
    pub fn buffer_range(&self, index: usize, offset: usize, length: usize, what: &str) -> Result<&[u8]> {
        let buffer =
            self.data.get(index).ok_or_else(|| VoxelError::MissingData(format!("{what}: no buffer {index}")))?;
        offset.checked_add(length).and_then(|end| buffer.get(offset..end)).ok_or_else(|| {
            VoxelError::Invalid(format!(
                "{what}: {length} bytes at {offset} run past the end of buffer {index} ({} bytes)",
                buffer.len()
            ))
        })
    }

    fn decode_meshopt(
        &self,
        view: &gltf::buffer::View<'_>,
        ext: &serde_json::Value,
        workspace: &mut Workspace,
    ) -> Result<Vec<u8>> {
        let what = format!("buffer view {} ({MESHOPT})", view.index());
        let invalid = |reason: String| VoxelError::Invalid(format!("{what}: {reason}"));
        let spec = MeshoptView::deserialize(ext).map_err(|e| invalid(e.to_string()))?;
        let mode = Mode::parse(&spec.mode).map_err(|_| invalid(format!("unknown mode {:?}", spec.mode)))?;
        let filter = Filter::parse(&spec.filter).map_err(|_| invalid(format!("unknown filter {:?}", spec.filter)))?;
        let expected = spec.count.checked_mul(spec.byte_stride).filter(|&n| n <= MAX_DECODED_VIEW);
        if expected != Some(view.length()) {
            return Err(invalid(format!(
                "{} elements of {} bytes do not make the view's {} bytes",
                spec.count,
                spec.byte_stride,
                view.length()
            )));
        }
        let source = self.buffer_range(spec.buffer, spec.byte_offset, spec.byte_length, &what)?;
        decode_buffer_view(mode, filter, spec.count, spec.byte_stride, source, workspace)
            .map_err(|e| invalid(format!("cannot decode ({e})")))
    }
}
