//! Settings declared once. From one list of fields (doc, type, default, value parser or clap
//! attributes, optionally its viewer control) a macro makes the settings struct (clap `Args` for
//! `render` and `view`, serde for the stats, the CSVs and the viewer's files, `DEFAULT` and
//! `Default` from the same defaults), its viewer controls (`CONTROLS`, drawn by the app through
//! `control` and `set_control`) and, where asked, its bench lists (`bench --NAME a,b,c`), so a
//! setting is one field, not five.
//!
//! - `knobs!`: a method's knobs (each field `name: Type = default, parse parser`).
//! - `declared!`: a settings type whose fields carry their own clap and serde attributes
//!   (`FrameSettings`): `pub name: Type = default[, ui "label" widget[, if |s| enabled][,
//!   paper_only = true]],`.
//! - `listed!`: `declared!` plus bench lists (`ClusterSettings`): a field marked `=> list "help"`
//!   also gets its bench list (same type, same value parser unless the list names its own, its
//!   default list and `--quick`'s), its resolution (`resolve`) and its combinations (`configs`).

/// Declares `$Settings` and `$Lists` (see the module). Each field: its doc comment, then
/// `name: Type = default, parse parser[, sweep [a, b]][, ui "label" control];` with
/// `parser(&str) -> Result<Type, Invalid>` and `control` a `settings::Widget`.
macro_rules! knobs {
    (
        $(#[doc = $sdoc:expr])*
        pub struct $Settings:ident, lists $Lists:ident, heading $heading:expr;
        $(
            $(#[doc = $doc:expr])*
            $field:ident: $ty:ty = $default:expr, parse $parser:path
                $(, sweep [$($sweep:expr),+ $(,)?])?
                $(, ui $label:literal $control:expr)?;
        )+
    ) => {
        $(#[doc = $sdoc])*
        #[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        #[cfg_attr(feature = "cli", derive(clap::Args))]
        #[cfg_attr(feature = "cli", command(next_help_heading = $heading))]
        #[serde(default)]
        pub struct $Settings {
            $(
                $(#[doc = $doc])*
                #[cfg_attr(feature = "cli", arg(long, default_value_t = $default, value_parser = $parser))]
                pub $field: $ty,
            )+
        }

        impl Default for $Settings {
            fn default() -> Self {
                $Settings {
                    $($field: $default,)+
                }
            }
        }

        impl $Settings {
            /// The knobs' names, in order: their CSV columns.
            pub const NAMES: &'static [&'static str] = &[$(stringify!($field)),+];

            /// The knobs' values as the CSV writes them, in the order of `NAMES`.
            pub fn values(&self) -> Vec<String> {
                vec![$(self.$field.to_string()),+]
            }

            /// The knobs the viewer shows, each with its label and control (`ui "label"
            /// control`), in order; the viewer draws them from this.
            pub const CONTROLS: &'static [$crate::settings::KnobWidget] = &[$($(
                $crate::settings::KnobWidget {
                    name: stringify!($field),
                    label: $label,
                    widget: $control,
                    paper_only: false,
                },
            )?)+];

            /// Knob `name`'s value as text (as `values` writes it); `None` when `name` is not
            /// one of these knobs.
            pub fn get(&self, name: &str) -> Option<String> {
                match name {
                    $(stringify!($field) => Some(self.$field.to_string()),)+
                    _ => None,
                }
            }

            /// Sets knob `name` from its text (as the CSV holds it) with its value parser; `None`
            /// when `name` is not one of these knobs.
            pub fn set(
                &mut self,
                name: &str,
                text: &str,
            ) -> Option<Result<(), $crate::settings::Invalid>> {
                match name {
                    $(stringify!($field) => Some($parser(text).map(|v| self.$field = v)),)+
                    _ => None,
                }
            }
        }

        $crate::settings::controls! {
            $Settings;
            $($field: $ty, accept |x| $parser(&x.to_string()).is_ok() $(, ui $label)?;)+
        }

        #[doc = concat!("`bench`'s lists of `", stringify!($Settings), "`'s knobs: a configuration takes one value of each (an empty list: the default).")]
        #[derive(Clone, Debug, Default, PartialEq)]
        #[cfg_attr(feature = "cli", derive(clap::Args))]
        #[cfg_attr(feature = "cli", command(next_help_heading = $heading))]
        pub struct $Lists {
            $(
                $(#[doc = $doc])*
                #[cfg_attr(feature = "cli", arg(long, value_name = "LIST", value_delimiter = ',', value_parser = $parser))]
                pub $field: Vec<$ty>,
            )+
        }

        impl $Lists {
            /// Every combination of the lists' values (the first knob outermost), repeats
            /// dropped; an empty list takes the default.
            pub fn configs(&self) -> Vec<$Settings> {
                let d = $Settings::default();
                let mut out = vec![d];
                $(
                    // An empty list: the knob's sweep list where it has one, else its default.
                    let default: Vec<$ty> = vec![$($($sweep),+)?];
                    let default = if default.is_empty() { vec![d.$field] } else { default };
                    let values: &[$ty] = if self.$field.is_empty() {
                        &default
                    } else {
                        &self.$field
                    };
                    out = out
                        .iter()
                        .flat_map(|&c| {
                            values.iter().map(move |&v| {
                                let mut n = c;
                                n.$field = v;
                                n
                            })
                        })
                        .collect();
                )+
                let mut unique: Vec<$Settings> = Vec::with_capacity(out.len());
                for c in out {
                    if !unique.contains(&c) {
                        unique.push(c);
                    }
                }
                unique
            }
        }
    };
}

pub(crate) use knobs;

/// Declares `$Settings` as written, its fields' defaults given beside them (see the module): a
/// field is `pub name: Type = default[, ui "label" widget[, if |s| enabled][, paper_only = true]]`, then
/// optionally `=> list ...` (read by `listed!`, ignored here), then `,`.
macro_rules! declared {
    (
        $(#[$smeta:meta])*
        pub struct $Settings:ident {
            $(
                $(#[$fmeta:meta])*
                pub $field:ident: $ty:ty = $default:expr
                $(, ui $label:literal $widget:expr $(, if $when:expr)? $(, paper_only = $paper_only:literal)?)?
                $(=> list $help:literal ($($larg:tt)*)
                    $(default [$($ldefault:expr),+])?
                    $(quick [$($quick:expr),+])?)?,
            )+
        }
    ) => {
        $(#[$smeta])*
        pub struct $Settings {
            $(
                $(#[$fmeta])*
                pub $field: $ty,
            )+
        }

        impl Default for $Settings {
            fn default() -> Self {
                Self::DEFAULT
            }
        }

        impl $Settings {
            /// The defaults, declared once beside the fields: the options' defaults
            /// (`default_value_t = DEFAULT.field`) and `Default`.
            pub const DEFAULT: $Settings = $Settings {
                $($field: $default,)+
            };

            /// The settings the viewer shows, each with its label and widget, in order; the
            /// viewer draws them from this.
            pub const CONTROLS: &'static [$crate::settings::KnobWidget] = &[$($(
                $crate::settings::KnobWidget {
                    name: stringify!($field),
                    label: $label,
                    widget: $widget,
                    paper_only: false $(|| $paper_only)?,
                },
            )?)+];
        }

        $crate::settings::controls! {
            $Settings;
            $($field: $ty, accept |_| true $(, ui $label $(, if $when)?)?;)+
        }
    };
}

pub(crate) use declared;

/// `Controlled` for a settings type's fields that declare a viewer control (for `knobs!` and
/// `declared!`): a control's value is its field's serde value, set back when it is one of the
/// field's and `accept` takes it (`knobs!`: the knob's value parser); `if` says when it applies.
macro_rules! controls {
    (
        $Settings:ident;
        $($field:ident: $ty:ty, accept $accept:expr $(, ui $label:literal $(, if $when:expr)?)?;)+
    ) => {
        impl $crate::settings::Controlled for $Settings {
            fn controls(&self) -> &'static [$crate::settings::KnobWidget] {
                Self::CONTROLS
            }

            fn control(&self, name: &str) -> Option<serde_json::Value> {
                match name {
                    $($(stringify!($field) => {
                        let _ = $label;
                        serde_json::to_value(&self.$field).ok()
                    })?)+
                    _ => None,
                }
            }

            fn set_control(&mut self, name: &str, v: serde_json::Value) -> bool {
                let _ = &v;
                match name {
                    $($(stringify!($field) => {
                        let _ = $label;
                        let accept: fn(&$ty) -> bool = $accept;
                        match serde_json::from_value::<$ty>(v) {
                            Ok(x) if accept(&x) => {
                                self.$field = x;
                                true
                            }
                            _ => false,
                        }
                    })?)+
                    _ => false,
                }
            }

            fn control_enabled(&self, name: &str) -> bool {
                match name {
                    $($(stringify!($field) => {
                        let _ = $label;
                        true $(&& {
                            let enabled: fn(&$Settings) -> bool = $when;
                            enabled(self)
                        })?
                    })?)+
                    _ => true,
                }
            }
        }
    };
}

pub(crate) use controls;

/// Declares `$Settings` with `declared!` and `$Lists`, its bench lists (see the module). A listed
/// field ends `=> list "help" (clap arguments of the list) [default [a, b]] [quick [c]],`. The
/// list's value parser is its own clap arguments' (none: clap's for the type).
macro_rules! listed {
    (
        $(#[$smeta:meta])*
        pub struct $Settings:ident { $($body:tt)* }
        $(#[$lmeta:meta])*
        pub struct $Lists:ident, heading $heading:expr;
    ) => {
        $crate::settings::knobs::declared! {
            $(#[$smeta])*
            pub struct $Settings { $($body)* }
        }
        $crate::settings::knobs::lists_of! {
            $Settings { $($body)* }
            $(#[$lmeta])*
            pub struct $Lists, heading $heading;
        }
    };
}

/// `listed!`'s bench lists of `$Settings`' fields marked `=> list`.
macro_rules! lists_of {
    (
        $Settings:ident {
            $(
                $(#[$fmeta:meta])*
                pub $field:ident: $ty:ty = $fdefault:expr
                $(, ui $label:literal $widget:expr $(, if $when:expr)? $(, paper_only = $paper_only:literal)?)?
                $(=> list $help:literal ($($larg:tt)*)
                    $(default [$($default:expr),+])?
                    $(quick [$($quick:expr),+])?)?,
            )+
        }
        $(#[$lmeta:meta])*
        pub struct $Lists:ident, heading $heading:expr;
    ) => {
        $(#[$lmeta])*
        #[derive(Clone, Debug, Default, PartialEq)]
        #[cfg_attr(feature = "cli", derive(clap::Args))]
        #[cfg_attr(feature = "cli", command(next_help_heading = $heading))]
        pub struct $Lists {
            $($(
                #[doc = $help]
                #[cfg_attr(feature = "cli", arg(long, value_name = "LIST", value_delimiter = ',', $($larg)*))]
                pub $field: Vec<$ty>,
            )?)+
        }

        impl $Lists {
            /// Every list with its values: an empty one at its `default` list (with `quick`, its
            /// `quick` list where it has one), or else the settings' default; repeats dropped.
            pub fn resolve(&self, quick: bool) -> $Lists {
                let d = <$Settings>::default();
                $Lists {
                    $($(
                        $field: {
                            let _ = $help;
                            let full: Vec<$ty> = vec![$($($default),+)?];
                            let fast: Vec<$ty> = vec![$($($quick),+)?];
                            let given = &self.$field;
                            let pick = if !given.is_empty() {
                                given.clone()
                            } else if quick && !fast.is_empty() {
                                fast
                            } else if !full.is_empty() {
                                full
                            } else {
                                vec![d.$field.clone()]
                            };
                            let mut unique: Vec<$ty> = Vec::with_capacity(pick.len());
                            for v in pick {
                                if !unique.contains(&v) {
                                    unique.push(v);
                                }
                            }
                            unique
                        },
                    )?)+
                }
            }

            /// Every combination of the lists' values on `base` (the first field outermost; an
            /// empty list keeps `base`'s value).
            pub fn configs(&self, base: &$Settings) -> Vec<$Settings> {
                let mut out = vec![base.clone()];
                $($(
                    let _ = $help;
                    if !self.$field.is_empty() {
                        out = out
                            .iter()
                            .flat_map(|c| {
                                self.$field.iter().map(move |v| {
                                    let mut n = c.clone();
                                    n.$field = v.clone();
                                    n
                                })
                            })
                            .collect();
                    }
                )?)+
                out
            }
        }
    };
}

pub(crate) use lists_of;

pub(crate) use listed;

#[cfg(test)]
mod tests {
    use super::super::{Controlled, Invalid, in_range};

    fn parse_small(v: &str) -> Result<u32, Invalid> {
        in_range(v, |n: u32| n < 10, "must be 0..=9")
    }

    fn parse_half(v: &str) -> Result<f32, Invalid> {
        in_range(v, |x: f32| (0.0..=1.0).contains(&x), "must be in [0, 1]")
    }

    knobs! {
        /// Two knobs.
        pub struct Pair, lists PairLists, heading "test";
        /// The first.
        a: u32 = 3, parse parse_small;
        /// The second.
        b: f32 = 0.5, parse parse_half, sweep [0.25, 0.75], ui "the b" super::super::Widget::log(0.1, 1.0);
    }

    /// One declaration gives the defaults, the names, the controls, the values as text, setting
    /// by text through the parser, the bench's combinations and serde.
    #[test]
    fn one_declaration_gives_defaults_names_values_and_combinations() {
        assert_eq!(Pair::default(), Pair { a: 3, b: 0.5 });
        assert_eq!(Pair::NAMES, &["a", "b"]);
        // Only `b` declares a control; its value reads back as its text.
        let c = super::super::KnobWidget {
            name: "b",
            label: "the b",
            widget: super::super::Widget::log(0.1, 1.0),
            paper_only: false,
        };
        assert_eq!(Pair::CONTROLS, &[c]);
        assert_eq!(Pair::default().get("b").as_deref(), Some("0.5"));
        assert_eq!(Pair::default().get("c"), None);
        assert_eq!(Pair { a: 7, b: 0.25 }.values(), vec!["7", "0.25"]);
        let mut p = Pair::default();
        assert_eq!(p.set("b", "0.25"), Some(Ok(())));
        assert_eq!(p, Pair { a: 3, b: 0.25 });
        assert!(matches!(p.set("a", "12"), Some(Err(_))));
        assert_eq!(p.set("c", "1"), None);
        let l = PairLists {
            a: vec![1, 2],
            b: vec![0.0, 1.0],
        };
        let want = [(1, 0.0), (1, 1.0), (2, 0.0), (2, 1.0)].map(|(a, b)| Pair { a, b });
        assert_eq!(l.configs(), want);
        // An empty list: the default, or the knob's sweep list.
        let swept = [(3, 0.25), (3, 0.75)].map(|(a, b)| Pair { a, b });
        assert_eq!(PairLists::default().configs(), swept);
        // serde: the field names, and a missing field takes its default.
        let j: Pair = serde_json::from_str(r#"{"a": 5}"#).unwrap();
        assert_eq!(j, Pair { a: 5, b: 0.5 });
        // The control's value is the field's serde value, set through the value parser.
        let mut p = Pair::default();
        assert_eq!(p.control("b"), Some(serde_json::json!(0.5)));
        assert!(p.set_control("b", serde_json::json!(0.25)));
        assert!(
            !p.set_control("b", serde_json::json!(2.0)),
            "the parser refuses 2"
        );
        assert!(!p.set_control("b", serde_json::json!("x")));
        assert_eq!(p, Pair { a: 3, b: 0.25 });
        assert_eq!(p.control("a"), None, "a declares no control");
    }

    use super::super::{Off, Widget};

    declared! {
        /// A group declared once, with its defaults and controls.
        #[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(default)]
        pub struct Group {
            /// On or off.
            pub on: bool = true, ui "on" Widget::Toggle,
            /// A count that applies when on; 0 is off.
            pub n: u32 = 3, ui "n" Widget::or("off", Off::Zero, Widget::int(1, 9), 2.0), if |g| g.on,
                paper_only = true,
            /// No control.
            pub hidden: f32 = 0.5,
        }
    }

    /// `declared!`: the defaults beside the fields give `DEFAULT` and `Default`; the controls'
    /// values are the fields' serde values; `if` and `paper_only` reach the viewer.
    #[test]
    fn one_declaration_gives_defaults_and_controls() {
        let d = Group {
            on: true,
            n: 3,
            hidden: 0.5,
        };
        assert_eq!((Group::DEFAULT, Group::default()), (d.clone(), d.clone()));
        let names: Vec<_> = Group::CONTROLS
            .iter()
            .map(|c| (c.name, c.paper_only))
            .collect();
        assert_eq!(names, [("on", false), ("n", true)]);
        assert_eq!(
            Group::CONTROLS[1].widget,
            Widget::Or {
                word: "off",
                off: Off::Zero,
                slider: super::super::Range {
                    lo: 1.0,
                    hi: 9.0,
                    log: false,
                    integer: true
                },
                start: 2.0
            }
        );
        let mut g = d.clone();
        assert_eq!(g.control("n"), Some(serde_json::json!(3)));
        assert!(Off::Zero.is(&serde_json::json!(0)) && !Off::Zero.is(&serde_json::json!(3)));
        assert!(g.set_control("n", Off::Zero.value()));
        assert_eq!(g.n, 0);
        assert!(g.set_control("n", Widget::number(true, 6.6)));
        assert_eq!(g.n, 7);
        assert!(
            !g.set_control("n", serde_json::json!(2.5)),
            "a u32 is not 2.5"
        );
        assert!(!g.set_control("n", serde_json::json!("x")));
        assert_eq!(
            (g.control("hidden"), g.set_control("hidden", 1.into())),
            (None, false)
        );
        assert!(g.control_enabled("n") && g.control_enabled("on"));
        assert!(g.set_control("on", false.into()));
        assert!(!g.control_enabled("n"), "n applies only when on");
    }

    /// With the feature `cli`, the same declaration is the command line: defaults, parsing with
    /// the parsers, and the bench's lists (repeats dropped by `configs`).
    #[cfg(feature = "cli")]
    #[test]
    fn one_declaration_gives_the_command_line() {
        use clap::Parser;
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            pair: Pair,
        }
        #[derive(clap::Parser)]
        struct Bench {
            #[command(flatten)]
            lists: PairLists,
        }
        assert_eq!(Cli::parse_from(["x"]).pair, Pair::default());
        assert_eq!(
            Cli::parse_from(["x", "--a", "7"]).pair,
            Pair { a: 7, b: 0.5 }
        );
        assert!(Cli::try_parse_from(["x", "--a", "12"]).is_err());
        let l = Bench::parse_from(["x", "--a", "1,2,1", "--b", "0,1"]).lists;
        let want = [(1, 0.0), (1, 1.0), (2, 0.0), (2, 1.0)].map(|(a, b)| Pair { a, b });
        assert_eq!(l.configs(), want);
        assert!(Bench::try_parse_from(["x", "--b", "0,2"]).is_err());
    }
}
