//! The developer variables (`FVPL_*`), checked like options before any work: a value the program
//! cannot use is one line and exit code 2 naming the variable, not a panic or a silent default
//! deep inside a run.

use crate::gpu::shader;
use crate::method;

/// Switches: set to 1 to turn on.
const SWITCHES: &[&str] = &[
    "FVPL_NO_ALPHA_TEST",
    "FVPL_NO_BOUNDS",
    "FVPL_NO_LOOPBOUND",
    "FVPL_PROFILE_STEPS",
    "FVPL_TRACE_BUFFERS",
];

/// Variables the test suite reads (not the program): known, so not warned about.
const TEST_ONLY: &[&str] = &[
    "FVPL_BOUNDS_UNMEASURED",
    "FVPL_FURNACE_SEEDS",
    "FVPL_MEASURE_BOUNDS",
    "FVPL_REQUIRE_SCENES",
    "FVPL_SKIP_LOG",
    "FVPL_TARGET_SCENE",
];

/// An integer variable's value in `lo..=hi`, or why not.
fn integer(name: &str, value: &str, lo: u32, hi: u32) -> Result<(), String> {
    match value.trim().parse::<u32>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(()),
        _ => Err(format!("{name}={value}: not an integer in {lo}..={hi}")),
    }
}

/// Checks every `FVPL_*` variable of the environment; returns warnings (names fuzzy-vpl does not
/// read, a typo most likely) or the first error.
pub fn check() -> Result<Vec<String>, String> {
    let mut warnings = Vec::new();
    let mut vars: Vec<(String, std::ffi::OsString)> = std::env::vars_os()
        .filter_map(|(k, v)| Some((k.into_string().ok()?, v)))
        .filter(|(k, _)| k.starts_with("FVPL_"))
        .collect();
    vars.sort();
    for (name, value) in vars {
        let Some(text) = value.to_str() else {
            return Err(format!("{name}: its value is not valid UTF-8"));
        };
        // The methods' own variables (each declared in its room).
        if let Some(v) = method::ENV_INTEGERS.iter().find(|v| v.name == name) {
            integer(&name, text, v.lo, v.hi)?;
            continue;
        }
        match name.as_str() {
            shader::SHADER_DIR_ENV => shader_dir(text)?,
            "FVPL_WORK_SCALE" => integer(&name, text, 1, u32::MAX)?,
            n if SWITCHES.contains(&n) => {
                if text != "1" {
                    return Err(format!(
                        "{name}={text}: a switch: set it to 1 to turn it on, or unset it"
                    ));
                }
            }
            n if TEST_ONLY.contains(&n) => {}
            _ => warnings.push(format!(
                "{name} is not a variable fuzzy-vpl reads (it reads {}, FVPL_WORK_SCALE, {}, {})",
                shader::SHADER_DIR_ENV,
                method::ENV_INTEGERS
                    .iter()
                    .map(|v| v.name)
                    .collect::<Vec<_>>()
                    .join(", "),
                SWITCHES.join(", ")
            )),
        }
    }
    Ok(warnings)
}

/// `FVPL_SHADER_DIR`: a folder from which every pass shader composes and validates (naga).
fn shader_dir(dir: &str) -> Result<(), String> {
    let env = shader::SHADER_DIR_ENV;
    if !std::path::Path::new(dir).is_dir() {
        return Err(format!("{env}={dir}: not a directory"));
    }
    for pass in shader::pass_names() {
        shader::try_compose(pass).map_err(|e| {
            format!("{e} (pass {pass}; {env} must hold every file of shaders-wgsl/)")
        })?;
        // Invalid WGSL would be a wgpu validation panic when its pipeline is made.
        shader::validate(pass).map_err(|e| {
            format!(
                "{env}={dir}: pass {pass} does not validate: {}",
                crate::panic_guard::one_line(&e)
            )
        })?;
    }
    Ok(())
}
