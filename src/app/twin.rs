//! The CPU twin of the viewer's display pass (`app::display`, `shaders-wgsl/display.wgsl`): the same
//! view of the same images as RGBA8, built from the viewer's CPU composition (`app::views`), which
//! the display pass replaces on the GPU.

use crate::app::views::{self, View};

/// A frame's images in the scene's units.
#[derive(Clone, Copy)]
pub struct Images<'a> {
    pub direct: &'a [[f32; 3]],
    pub indirect: &'a [[f32; 3]],
}

/// What the display pass draws for `view` (FLIP without a reference: the final view), and the
/// exposure it used: the fixed one, or `exposure::auto_exposure` of A's radiance.
#[allow(clippy::too_many_arguments)]
pub fn display(
    view: View,
    a: Images,
    b: Option<Images>,
    reference: Option<&[[f32; 3]]>,
    labels: Option<&[u32]>,
    exposure: crate::exposure::Exposure,
    direct_on: bool,
    split: f32,
    (w, h): (u32, u32),
) -> (Vec<u8>, f32) {
    let radiance: Vec<[f32; 3]> = a
        .direct
        .iter()
        .zip(a.indirect)
        .map(|(d, i)| [0, 1, 2].map(|c| (d[c] + i[c]).min(f32::MAX)))
        .collect();
    let e = exposure.resolve(&radiance);
    let fin = |x: Images| views::final_image(x.direct, x.indirect, direct_on);
    let b = b.unwrap_or(a);
    let no_ref = vec![[0.0; 3]; radiance.len()];
    let flip_ref = reference;
    let reference = reference.unwrap_or(&no_ref);
    let img = match view {
        View::Direct => views::tonemap(a.direct, e),
        View::Indirect => views::tonemap(a.indirect, e),
        View::SpClusters => views::sp_clusters(labels.expect("labels"), &radiance, e),
        View::VplPoints => views::tonemap(&fin(a), e)
            .chunks(4)
            .flat_map(|p| [p[0] / 3, p[1] / 3, p[2] / 3, 255])
            .collect(),
        View::Reference => views::tonemap(reference, e),
        View::Error => views::error(&radiance, reference),
        View::Split => views::split(
            &views::tonemap(&fin(a), e),
            &views::tonemap(&fin(b), e),
            w,
            h,
            split,
        ),
        View::Diff => views::error(&fin(a), &fin(b)),
        View::Flip => match flip_ref {
            Some(r) => views::flip(&radiance, r, w, h, e),
            None => views::tonemap(&fin(a), e),
        },
        View::Final => views::tonemap(&fin(a), e),
    };
    (img, e)
}
