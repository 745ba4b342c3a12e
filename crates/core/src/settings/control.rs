//! A setting's viewer control as data: the core describes it (`Widget`, `KnobWidget`, declared
//! with the setting's field by `knobs!`, `declared!` and `listed!`), the app draws it (the core
//! knows no UI toolkit). A control's value travels as the field's serde value
//! (`serde_json::Value`): a number, a bool, an enum's name, `"auto"`, or null for an absent
//! option, read and set by the generated `control` and `set_control`.

/// How the viewer shows a setting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Widget {
    /// A slider (its range is widened to hold a value given outside it).
    Slider(Range),
    /// One of these values (each the field's serde name, and its label).
    Choice(&'static [(&'static str, &'static str)]),
    /// On or off (a bool).
    Toggle,
    /// A word or a number on a slider: the field's value `off` is shown as a ticked box labelled
    /// `word` (`auto`, `off`), any other as the number; unticking starts the slider at `start` (or
    /// at the last number the panel showed).
    Or {
        word: &'static str,
        off: Off,
        slider: Range,
        start: f64,
    },
    /// A cosine, shown as its angle in degrees on a slider over [0, 180].
    Cosine,
}

/// A slider's values: [lo, hi]; `log`: a logarithmic scale; `integer`: whole numbers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
    pub integer: bool,
}

impl Range {
    /// The serde values of the slider's two ends.
    pub fn ends(self) -> [serde_json::Value; 2] {
        [self.lo, self.hi].map(|x| Widget::number(self.integer, x))
    }
}

/// The serde value an `Or` field takes for its word.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Off {
    /// An absent option (`Option::None`, serde's null).
    Null,
    /// A name (`Gamma::Auto` is `"auto"`).
    Name(&'static str),
    /// The number 0 (a K of 0: that clustering does not run).
    Zero,
}

impl Off {
    /// Whether serde value `v` is this word.
    pub fn is(self, v: &serde_json::Value) -> bool {
        match self {
            Off::Null => v.is_null(),
            Off::Name(n) => v.as_str() == Some(n),
            Off::Zero => v.as_f64() == Some(0.0),
        }
    }

    /// The serde value of the word.
    pub fn value(self) -> serde_json::Value {
        match self {
            Off::Null => serde_json::Value::Null,
            Off::Name(n) => n.into(),
            Off::Zero => 0.into(),
        }
    }
}

impl Widget {
    /// Whole numbers in [lo, hi] on a linear slider.
    pub const fn int(lo: u32, hi: u32) -> Widget {
        Widget::Slider(Range {
            lo: lo as f64,
            hi: hi as f64,
            log: false,
            integer: true,
        })
    }

    /// Whole numbers in [lo, hi] on a logarithmic slider.
    pub const fn int_log(lo: u32, hi: u32) -> Widget {
        Widget::Slider(Range {
            lo: lo as f64,
            hi: hi as f64,
            log: true,
            integer: true,
        })
    }

    /// Numbers in [lo, hi] on a linear slider.
    pub const fn linear(lo: f64, hi: f64) -> Widget {
        Widget::Slider(Range {
            lo,
            hi,
            log: false,
            integer: false,
        })
    }

    /// Numbers in [lo, hi] on a logarithmic slider.
    pub const fn log(lo: f64, hi: f64) -> Widget {
        Widget::Slider(Range {
            lo,
            hi,
            log: true,
            integer: false,
        })
    }

    /// `word` (the value `off`) or a number on `slider`, which starts at `start`.
    pub const fn or(word: &'static str, off: Off, slider: Widget, start: f64) -> Widget {
        match slider {
            Widget::Slider(slider) => Widget::Or {
                word,
                off,
                slider,
                start,
            },
            _ => panic!("Widget::or takes a slider"),
        }
    }

    /// The serde value a slider position `x` sets: a whole number for an integer slider (serde
    /// reads no `u32` from a float).
    pub fn number(integer: bool, x: f64) -> serde_json::Value {
        if integer {
            serde_json::Value::from(x.round().max(0.0) as u64)
        } else {
            serde_json::Value::from(x)
        }
    }
}

/// A setting in the viewer: its field's name (its option and column), its label, its widget, and
/// whether only the method whose knobs are the paper's (`MethodEntry::own_settings` false) uses it (the
/// viewer greys it out for the others).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnobWidget {
    pub name: &'static str,
    pub label: &'static str,
    pub widget: Widget,
    pub paper_only: bool,
}

/// A settings type whose fields declare viewer controls (`knobs!`, `declared!`, `listed!`, and a
/// method's `MethodSettings`): what the viewer draws and how it reads and sets each value.
pub trait Controlled {
    /// The controls, in order.
    fn controls(&self) -> &'static [KnobWidget];
    /// Control `name`'s value (its field's serde value); `None` for a field without one.
    fn control(&self, name: &str) -> Option<serde_json::Value>;
    /// Sets control `name` from a serde value; false (and nothing set) when the value is not one
    /// of the field's or the field refuses it.
    fn set_control(&mut self, name: &str, v: serde_json::Value) -> bool;
    /// Whether control `name` applies with the other settings as they are (a field's `if`).
    fn control_enabled(&self, name: &str) -> bool {
        let _ = name;
        true
    }
}
