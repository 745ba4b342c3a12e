//! Accessor decoding with full bounds checking: byte strides, sparse substitution, every component
//! type (normalised or not, as `KHR_mesh_quantization` allows). Malformed data gives an `Err` with a
//! short message, never a panic or an out-of-bounds read.

use gltf::accessor::{DataType, Dimensions};

/// Component count of an accessor type.
fn components(d: Dimensions) -> usize {
    match d {
        Dimensions::Scalar => 1,
        Dimensions::Vec2 => 2,
        Dimensions::Vec3 => 3,
        Dimensions::Vec4 | Dimensions::Mat2 => 4,
        Dimensions::Mat3 => 9,
        Dimensions::Mat4 => 16,
    }
}

fn type_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

/// The bytes `[offset, offset + len)` of buffer view `view`, checked against the loaded buffer.
fn view_bytes<'b>(
    view: &gltf::buffer::View,
    buffers: &'b [Vec<u8>],
    what: &str,
) -> Result<&'b [u8], String> {
    let buffer = view.buffer().index();
    let data = buffers
        .get(buffer)
        .ok_or_else(|| format!("{what}: buffer {buffer} was not loaded"))?;
    let start = view.offset();
    let end = start
        .checked_add(view.length())
        .filter(|&e| e <= data.len())
        .ok_or_else(|| {
            format!(
                "{what}: bufferView {} (bytes {}..{}) lies outside buffer {} ({} bytes)",
                view.index(),
                start,
                start as u128 + view.length() as u128,
                buffer,
                data.len()
            )
        })?;
    Ok(&data[start..end])
}

/// Checks that `count` elements of `elem` bytes, `stride` apart, starting at `offset`, fit in `len`.
fn check_fits(
    offset: usize,
    stride: usize,
    elem: usize,
    count: usize,
    len: usize,
) -> Result<(), String> {
    if count == 0 {
        return Ok(());
    }
    let need = (offset as u128) + (stride as u128) * (count as u128 - 1) + elem as u128;
    if need > len as u128 {
        Err(format!(
            "needs {need} bytes but its bufferView holds only {len} (buffer too short)"
        ))
    } else {
        Ok(())
    }
}

/// Most elements an accessor without a bufferView (all zeros plus sparse values) may declare.
const MAX_VIEWLESS: usize = 1 << 24;

/// Decodes every element of the accessor with `decode` (given `accessor.size()` bytes), applying
/// sparse substitutes. All bounds are checked before anything is allocated.
fn visit<T: Clone>(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
    decode: impl Fn(&[u8]) -> T,
) -> Result<Vec<T>, String> {
    let n = components(acc.dimensions());
    let elem = n * acc.data_type().size();
    let count = acc.count();
    let ctx = |msg: String| format!("{what} (accessor {}) {msg}", acc.index());

    // Dense part: (bytes, offset, stride), checked.
    let dense = match acc.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers, what)?;
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(ctx(format!(
                    "has byteStride {stride}, smaller than its element size {elem}"
                )));
            }
            check_fits(acc.offset(), stride, elem, count, bytes.len()).map_err(ctx)?;
            Some((bytes, acc.offset(), stride))
        }
        None if count > MAX_VIEWLESS => {
            return Err(ctx(format!(
                "has no bufferView and an implausible count {count}"
            )));
        }
        None => None,
    };

    // Sparse part: (count, index bytes, index offset, index size, value bytes, value offset).
    let sparse = match acc.sparse() {
        Some(sparse) => {
            let scount = sparse.count();
            let idx = sparse.indices();
            let isize = match idx.index_type() {
                gltf::accessor::sparse::IndexType::U8 => 1,
                gltf::accessor::sparse::IndexType::U16 => 2,
                gltf::accessor::sparse::IndexType::U32 => 4,
            };
            let ibytes = view_bytes(&idx.view(), buffers, what)?;
            check_fits(idx.offset(), isize, isize, scount, ibytes.len())
                .map_err(|m| ctx(format!("sparse indices {m}")))?;
            let vals = sparse.values();
            let vbytes = view_bytes(&vals.view(), buffers, what)?;
            check_fits(vals.offset(), elem, elem, scount, vbytes.len())
                .map_err(|m| ctx(format!("sparse values {m}")))?;
            Some((scount, ibytes, idx.offset(), isize, vbytes, vals.offset()))
        }
        None => None,
    };

    let mut out = match dense {
        Some((bytes, offset, stride)) => (0..count)
            .map(|i| {
                let at = offset + i * stride;
                decode(&bytes[at..at + elem])
            })
            .collect(),
        None => vec![decode(&vec![0u8; elem]); count],
    };

    if let Some((scount, ibytes, ioff, isize, vbytes, voff)) = sparse {
        for k in 0..scount {
            let at = ioff + k * isize;
            let target = read_uint(&ibytes[at..at + isize]) as usize;
            if target >= count {
                return Err(ctx(format!(
                    "has sparse index {target} out of range (count {count})"
                )));
            }
            let v = voff + k * elem;
            out[target] = decode(&vbytes[v..v + elem]);
        }
    }
    Ok(out)
}

/// A little-endian unsigned integer of 1, 2 or 4 bytes.
fn read_uint(b: &[u8]) -> u32 {
    match b.len() {
        1 => b[0] as u32,
        2 => u16::from_le_bytes([b[0], b[1]]) as u32,
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// One component as f32, normalised per the glTF rules when `normalized` is set.
fn component(b: &[u8], ty: DataType, normalized: bool) -> f32 {
    match ty {
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        DataType::I8 => {
            let v = b[0] as i8 as f32;
            if normalized { (v / 127.0).max(-1.0) } else { v }
        }
        DataType::U8 => {
            let v = b[0] as f32;
            if normalized { v / 255.0 } else { v }
        }
        DataType::I16 => {
            let v = i16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U16 => {
            let v = u16::from_le_bytes([b[0], b[1]]) as f32;
            if normalized { v / 65535.0 } else { v }
        }
        DataType::U32 => {
            let v = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64;
            (if normalized { v / u32::MAX as f64 } else { v }) as f32
        }
    }
}

/// Reads an accessor of `N` components per element as floats.
pub(super) fn read_floats<const N: usize>(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<[f32; N]>, String> {
    if components(acc.dimensions()) != N || matches!(acc.dimensions(), Dimensions::Mat2) {
        return Err(format!(
            "{what} (accessor {}) has type {}, expected {} components",
            acc.index(),
            type_name(acc.dimensions()),
            N
        ));
    }
    let ty = acc.data_type();
    let csize = ty.size();
    let normalized = acc.normalized();
    visit(acc, buffers, what, |b| {
        std::array::from_fn(|c| component(&b[c * csize..(c + 1) * csize], ty, normalized))
    })
}

/// Reads an index accessor (SCALAR of U8, U16 or U32).
pub(super) fn read_indices(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<u32>, String> {
    let ty = acc.data_type();
    if acc.dimensions() != Dimensions::Scalar
        || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32)
    {
        return Err(format!(
            "{what} (accessor {}) must be a SCALAR of unsigned byte, short or int",
            acc.index()
        ));
    }
    visit(acc, buffers, what, read_uint)
}
