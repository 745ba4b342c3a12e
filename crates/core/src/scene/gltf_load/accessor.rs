//! Accessor decoding: the `gltf` crate's accessor iterator (`gltf::accessor::Iter`: byte strides,
//! sparse substitution) behind bounds checks, for every component type (normalised or not, as
//! `KHR_mesh_quantization` allows). Malformed data gives an `Err` with a short message, never a
//! panic or an out-of-bounds read.
//!
//! Not `gltf::mesh::Reader`: its `read_positions` and `read_normals` take every accessor as f32
//! (quantised positions would be read as garbage), its `read_tex_coords`, `read_colors` and
//! `read_indices` end in `unreachable!()` on a component type they do not expect, and it ignores
//! `normalized`.

use gltf::accessor::{DataType, Dimensions, Item, Iter};

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

/// glTF's alignment rule: data of components of `size` bytes starts at a multiple of `size` both
/// in its bufferView (`offset`) and in its buffer (`offset` + the view's `view_offset`); a file that
/// breaks it is refused, as the specification requires, not read from the byte it names.
fn aligned(offset: usize, view_offset: usize, size: usize, what: &str) -> Result<(), String> {
    if !offset.is_multiple_of(size)
        || !(offset as u128 + view_offset as u128).is_multiple_of(size as u128)
    {
        return Err(format!(
            "is misaligned: {what} start at byteOffset {offset} in a bufferView at byteOffset {view_offset} of its buffer, and both must be multiples of the component size {size} (glTF requires it)"
        ));
    }
    Ok(())
}

/// Most elements an accessor without a bufferView (all zeros plus sparse values) may declare.
const MAX_VIEWLESS: usize = 1 << 24;

/// Checks every bound `gltf::accessor::Iter` relies on before it is built: it slices buffers and
/// computes `count - 1` unchecked (a count of 0, a view or element past its buffer's end, a stride
/// smaller than an element would panic or read a wrong element), takes a sparse view's byteStride
/// where glTF forbids one, and skips a sparse index that is out of range or out of order without a
/// word. Returns whether the accessor has elements at all.
fn check(acc: &gltf::Accessor, buffers: &[Vec<u8>], what: &str) -> Result<bool, String> {
    let elem = components(acc.dimensions()) * acc.data_type().size();
    let count = acc.count();
    let ctx = |msg: String| format!("{what} (accessor {}) {msg}", acc.index());
    match acc.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers, what)?;
            let size = acc.data_type().size();
            aligned(acc.offset(), view.offset(), size, "its data").map_err(ctx)?;
            if let Some(s) = view.stride().filter(|s| !s.is_multiple_of(size)) {
                return Err(ctx(format!(
                    "has byteStride {s}, not a multiple of its component size {size} (glTF requires one)"
                )));
            }
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(ctx(format!(
                    "has byteStride {stride}, smaller than its element size {elem}"
                )));
            }
            check_fits(acc.offset(), stride, elem, count, bytes.len()).map_err(ctx)?;
        }
        None if count > MAX_VIEWLESS => {
            return Err(ctx(format!(
                "has no bufferView and an implausible count {count}"
            )));
        }
        None => {}
    }
    let Some(sparse) = acc.sparse() else {
        return Ok(count > 0);
    };
    let scount = sparse.count();
    if scount == 0 {
        return Err(ctx(
            "has a sparse count of 0 (at least 1 is required)".into()
        ));
    }
    let idx = sparse.indices();
    let vals = sparse.values();
    if idx.view().stride().is_some() || vals.view().stride().is_some() {
        return Err(ctx(
            "has a sparse bufferView with a byteStride, which glTF forbids".into(),
        ));
    }
    let isize = idx.index_type().size();
    aligned(
        idx.offset(),
        idx.view().offset(),
        isize,
        "its sparse indices",
    )
    .map_err(ctx)?;
    let size = acc.data_type().size();
    aligned(
        vals.offset(),
        vals.view().offset(),
        size,
        "its sparse values",
    )
    .map_err(ctx)?;
    let ibytes = view_bytes(&idx.view(), buffers, what)?;
    check_fits(idx.offset(), isize, isize, scount, ibytes.len())
        .map_err(|m| ctx(format!("sparse indices {m}")))?;
    let vbytes = view_bytes(&vals.view(), buffers, what)?;
    check_fits(vals.offset(), elem, elem, scount, vbytes.len())
        .map_err(|m| ctx(format!("sparse values {m}")))?;
    let mut previous = None;
    for k in 0..scount {
        let at = idx.offset() + k * isize;
        let b = &ibytes[at..at + isize];
        let target = match isize {
            1 => b[0] as usize,
            2 => u16::from_le_bytes([b[0], b[1]]) as usize,
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
        };
        if target >= count {
            return Err(ctx(format!(
                "has sparse index {target} out of range (count {count})"
            )));
        }
        if previous.is_some_and(|p| target <= p) {
            return Err(ctx(format!(
                "has sparse index {target} after {}: the indices must strictly increase",
                previous.unwrap_or(0)
            )));
        }
        previous = Some(target);
    }
    Ok(count > 0)
}

/// Every element of a checked accessor through the `gltf` crate's iterator (strides, sparse
/// substitution, zeros for a sparse accessor without a bufferView).
fn elements<T: Item>(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<T>, String> {
    if !check(acc, buffers, what)? {
        return Ok(Vec::new());
    }
    let iter = Iter::<T>::new(acc.clone(), |b: gltf::Buffer| {
        buffers.get(b.index()).map(Vec::as_slice)
    })
    .ok_or_else(|| format!("{what} (accessor {}) cannot be read", acc.index()))?;
    Ok(iter.collect())
}

/// A component type and its conversion to f32, normalised per the glTF rules when asked.
trait Component: Copy {
    fn to_f32(self, normalized: bool) -> f32;
}

impl Component for f32 {
    fn to_f32(self, _: bool) -> f32 {
        self
    }
}

impl Component for i8 {
    fn to_f32(self, normalized: bool) -> f32 {
        let v = self as f32;
        if normalized { (v / 127.0).max(-1.0) } else { v }
    }
}

impl Component for u8 {
    fn to_f32(self, normalized: bool) -> f32 {
        let v = self as f32;
        if normalized { v / 255.0 } else { v }
    }
}

impl Component for i16 {
    fn to_f32(self, normalized: bool) -> f32 {
        let v = self as f32;
        if normalized {
            (v / 32767.0).max(-1.0)
        } else {
            v
        }
    }
}

impl Component for u16 {
    fn to_f32(self, normalized: bool) -> f32 {
        let v = self as f32;
        if normalized { v / 65535.0 } else { v }
    }
}

impl Component for u32 {
    fn to_f32(self, normalized: bool) -> f32 {
        let v = self as f64;
        (if normalized { v / u32::MAX as f64 } else { v }) as f32
    }
}

/// The elements of an accessor of component type `C`, as floats.
fn floats_of<C: Component, const N: usize>(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<[f32; N]>, String>
where
    [C; N]: Item,
{
    let normalized = acc.normalized();
    Ok(elements::<[C; N]>(acc, buffers, what)?
        .into_iter()
        .map(|e| e.map(|c| c.to_f32(normalized)))
        .collect())
}

/// Reads an accessor of `N` components per element as floats.
pub(super) fn read_floats<const N: usize>(
    acc: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<[f32; N]>, String>
where
    [f32; N]: Item,
    [i8; N]: Item,
    [u8; N]: Item,
    [i16; N]: Item,
    [u16; N]: Item,
    [u32; N]: Item,
{
    if components(acc.dimensions()) != N || matches!(acc.dimensions(), Dimensions::Mat2) {
        return Err(format!(
            "{what} (accessor {}) has type {}, expected {} components",
            acc.index(),
            type_name(acc.dimensions()),
            N
        ));
    }
    match acc.data_type() {
        DataType::F32 => floats_of::<f32, N>(acc, buffers, what),
        DataType::I8 => floats_of::<i8, N>(acc, buffers, what),
        DataType::U8 => floats_of::<u8, N>(acc, buffers, what),
        DataType::I16 => floats_of::<i16, N>(acc, buffers, what),
        DataType::U16 => floats_of::<u16, N>(acc, buffers, what),
        DataType::U32 => floats_of::<u32, N>(acc, buffers, what),
    }
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
    Ok(match ty {
        DataType::U8 => elements::<u8>(acc, buffers, what)?
            .into_iter()
            .map(u32::from)
            .collect(),
        DataType::U16 => elements::<u16>(acc, buffers, what)?
            .into_iter()
            .map(u32::from)
            .collect(),
        _ => elements::<u32>(acc, buffers, what)?,
    })
}
