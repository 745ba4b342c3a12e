//! Automatic exposure for display (PNG and the viewer): the log-average luminance of the image is
//! mapped to the middle-grey key value 0.18 (Reinhard, Stark, Shirley and Ferwerda 2002, "Photographic
//! tone reproduction for digital images", Eq. 1–2). EXR output stays linear and unscaled.

/// The key value a of Reinhard et al. (2002): the log-average luminance is shown as this (linear,
/// before the sRGB transfer: about 46 % grey).
pub const KEY: f64 = 0.18;

/// The exposure of a display image: fixed (`--exposure E`) or automatic (`--exposure auto`, the
/// default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    Auto,
    Fixed(f32),
}

impl Exposure {
    /// Parses `auto` or a finite number ≥ 0 (clap value parser).
    pub fn parse(s: &str) -> Result<Exposure, String> {
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Exposure::Auto);
        }
        match s.parse::<f32>() {
            Ok(e) if e.is_finite() && e >= 0.0 => Ok(Exposure::Fixed(e)),
            _ => Err(format!("'{s}' is neither auto nor a finite number >= 0")),
        }
    }

    /// The exposure used for `radiance`: the fixed value, or `auto_exposure(radiance)`.
    pub fn resolve(self, radiance: &[[f32; 3]]) -> f32 {
        match self {
            Exposure::Fixed(e) => e,
            Exposure::Auto => auto_exposure(radiance),
        }
    }

    pub fn is_auto(self) -> bool {
        self == Exposure::Auto
    }
}

/// As the command line writes it: `auto` or the factor.
impl std::fmt::Display for Exposure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Exposure::Auto => f.write_str("auto"),
            Exposure::Fixed(e) => write!(f, "{e}"),
        }
    }
}

/// Serialised as the command line writes it: `"auto"` or the factor.
impl serde::Serialize for Exposure {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Exposure::Auto => s.serialize_str("auto"),
            Exposure::Fixed(e) => s.serialize_f32(*e),
        }
    }
}

impl<'de> serde::Deserialize<'de> for Exposure {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Exposure, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(untagged)]
        enum Raw {
            N(f32),
            S(String),
        }
        match Raw::deserialize(d)? {
            Raw::N(e) => Exposure::parse(&e.to_string()),
            Raw::S(s) => Exposure::parse(&s),
        }
        .map_err(serde::de::Error::custom)
    }
}

/// The log-average luminance exp(mean ln L) over the pixels with a finite luminance L > 0 (in f64),
/// or `None` when there is none. Reinhard et al. add a small δ inside the log to allow black pixels;
/// here black pixels (misses, unlit surfaces) are left out instead, which keeps the rule scale-free:
/// an image scaled by k has its log-average scaled by exactly k.
pub fn log_average_luminance(radiance: &[[f32; 3]]) -> Option<f64> {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for p in radiance {
        let l = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
        if l.is_finite() && l > 0.0 {
            sum += l.ln();
            n += 1;
        }
    }
    (n > 0).then(|| (sum / n as f64).exp())
}

/// The exposure that maps the image's log-average luminance to `KEY`: KEY / L̄. An image without a
/// lit pixel gets 1. Kept within f32's positive normal range (1.2e-38..3.4e38), which covers every
/// log-average of the accepted light range (emitters of 1e-44..1e36) but its last five decades
/// (an image darker than about 5e-40 on average, where f32 itself is denormal); there the PNG
/// writer warns that the image is black (`export::write_image`). `to_srgb8` multiplies in f64, so
/// no pixel overflows.
pub fn auto_exposure(radiance: &[[f32; 3]]) -> f32 {
    match log_average_luminance(radiance) {
        Some(l) => (KEY / l).clamp(f32::MIN_POSITIVE as f64, f32::MAX as f64) as f32,
        None => 1.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked: grey pixels of luminance 0.01, 0.1, 1 and 10 (plus a black and a NaN pixel,
    /// left out) have the log-average (0.01 · 0.1 · 1 · 10)^(1/4) = 0.01^(1/4) = 0.316228, so the
    /// exposure is 0.18 / 0.316228 = 0.569210.
    #[test]
    fn log_average_of_four_greys() {
        let img = [
            [0.01; 3],
            [0.1; 3],
            [1.0; 3],
            [10.0; 3],
            [0.0; 3],
            [f32::NAN, 0.0, 0.0],
        ];
        let l = log_average_luminance(&img).unwrap();
        assert!((l - 0.316_227_8).abs() < 1e-6, "{l}");
        let e = auto_exposure(&img);
        // f32 rounding of the inputs (0.01, 0.1 are not exact): agreement to 1e-6 relative.
        assert!((e / 0.569_210 - 1.0).abs() < 1e-5, "{e}");
    }

    /// Scale-free: the image × k gets the exposure / k (relative 1e-6: f64 sums of f32 inputs), even
    /// at k = 1e-20 and 1e20; a black image gets 1; the middle-grey image gets exactly its key.
    #[test]
    fn scale_free_and_black() {
        let img: Vec<[f32; 3]> = (0..100)
            .map(|i| [0.01 * i as f32, 0.02 * i as f32, 0.005 * i as f32])
            .collect();
        let e = auto_exposure(&img) as f64;
        for k in [1e-20f32, 1e-3, 7.0, 1e20] {
            let scaled: Vec<[f32; 3]> = img.iter().map(|p| p.map(|c| c * k)).collect();
            let ek = auto_exposure(&scaled) as f64;
            assert!((ek * k as f64 / e - 1.0).abs() < 1e-6, "k {k}: {ek} vs {e}");
        }
        assert_eq!(auto_exposure(&[[0.0; 3]; 4]), 1.0);
        // The faint and bright ends of the light range `--light-scale` accepts (1e-44..1e36):
        // a grey image of 1e-36 is exposed by 1.8e35 (the former 1e30 cap left it black), one of
        // 1e36 by 1.8e-37 (the former 1e-30 cap made it white).
        for l in [1e-36f32, 1e36] {
            let e = auto_exposure(&[[l; 3]; 4]) as f64;
            assert!((e * l as f64 / KEY - 1.0).abs() < 1e-5, "{l}: {e}");
        }
        // Below f32's normal range the exposure stops at f32::MAX.
        assert_eq!(auto_exposure(&[[1e-44; 3]; 4]), f32::MAX);
        assert!((auto_exposure(&[[0.18; 3]; 4]) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn parses_auto_and_numbers() {
        assert_eq!(Exposure::parse("auto"), Ok(Exposure::Auto));
        assert_eq!(Exposure::parse("2.5"), Ok(Exposure::Fixed(2.5)));
        assert!(Exposure::parse("-1").is_err());
        assert!(Exposure::parse("NaN").is_err());
        assert!(Exposure::parse("bright").is_err());
    }
}
