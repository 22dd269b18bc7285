//! The document's buffers, and the bytes of each buffer view: checked against their buffer, or decoded from
//! EXT_meshopt_compression (all modes and filters, via `meshoptimizer-rs`), whose fallback buffers are never
//! read.

use std::collections::HashMap;
use std::path::Path;

use meshoptimizer_rs::codec::{Filter, Mode, decode_buffer_view};
use meshoptimizer_rs::{Limits, Workspace};
use serde::Deserialize;

use crate::error::{Result, VoxelError};

const MESHOPT: &str = "EXT_meshopt_compression";

/// The most bytes one meshopt buffer view may decode to (a guard against absurd counts in hostile files).
const MAX_DECODED_VIEW: usize = 1 << 29;

/// The buffers of a document and the decoded bytes of its meshopt-compressed views.
pub(crate) struct Buffers {
    /// Buffer contents by buffer index (a meshopt fallback buffer is empty).
    pub data: Vec<gltf::buffer::Data>,
    /// Decoded bytes of compressed buffer views, by view index.
    decoded: HashMap<usize, Vec<u8>>,
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

impl Buffers {
    /// Loads every buffer (GLB blob, data URI or file next to `base_dir`), then decodes compressed views.
    pub fn load(document: &gltf::Document, base_dir: Option<&Path>, mut blob: Option<Vec<u8>>) -> Result<Self> {
        let mut data = Vec::new();
        for buffer in document.buffers() {
            let what = format!("buffer {}", buffer.index());
            if is_meshopt_fallback(&buffer) {
                data.push(gltf::buffer::Data(Vec::new()));
                continue;
            }
            let bytes = gltf::buffer::Data::from_source_and_blob(buffer.source(), base_dir, &mut blob)
                .map_err(|e| VoxelError::MissingData(format!("{what}: {e}")))?;
            if bytes.len() < buffer.length() {
                return Err(VoxelError::MissingData(format!(
                    "{what}: {} bytes where the file declares {}",
                    bytes.len(),
                    buffer.length()
                )));
            }
            data.push(bytes);
        }
        let mut buffers = Self { data, decoded: HashMap::new() };
        let mut workspace = Workspace::new(Limits { max_bytes: MAX_DECODED_VIEW, ..Limits::default() });
        for view in document.views() {
            if let Some(ext) = view.extension_value(MESHOPT) {
                let decoded = buffers.decode_meshopt(&view, ext, &mut workspace)?;
                buffers.decoded.insert(view.index(), decoded);
            }
        }
        Ok(buffers)
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
