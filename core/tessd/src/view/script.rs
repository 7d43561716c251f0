//! `--script ACTIONS.json`: a list of actions the viewer plays one per frame, for tests,
//! benchmarks and recorded flights. Each action is an object with one key:
//! `{"wait": FRAMES}`, `{"camera": {"eye", "target", "up", "fov"}}`, `{"orbit": [DX, DY]}`
//! (degrees), `{"zoom": FACTOR}`, `{"key": "w"}`, `{"until_idle": true}`,
//! `{"screenshot": PATH, "face_ids": PATH, "overlay": true}` (`face_ids` and `overlay`, the
//! heads-up text and help as the window shows them, optional), `{"stats": PATH}`,
//! `{"quit": true}`.

use anyhow::{Context, Result, bail};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One scripted action.
#[derive(Clone, Debug, PartialEq)]
pub enum Action {
    /// Draw this many frames before the next action.
    Wait(u32),
    /// Put the camera here (`fov` in degrees; the current one when absent).
    Camera {
        /// Eye position.
        eye: [f64; 3],
        /// The point looked at.
        target: [f64; 3],
        /// Up direction.
        up: [f64; 3],
        /// Vertical field of view.
        fov: Option<f64>,
    },
    /// Orbit by these degrees (horizontal, vertical).
    Orbit(f64, f64),
    /// Zoom: the distance to the target times this factor.
    Zoom(f64),
    /// Press a key (the names of the help overlay: `w`, `plus`, `bracketright`, `home`...).
    Key(String),
    /// Wait until the background work (LOD chains, decoding, subdivision) is done.
    UntilIdle,
    /// Save the next frame's colour (and its face ids, encoded as `tessd render` does).
    Screenshot {
        /// The colour PNG.
        color: PathBuf,
        /// The face-id PNG.
        face_ids: Option<PathBuf>,
        /// With the heads-up text and help, as the window shows them (else the bare frame).
        overlay: bool,
    },
    /// Write the statistics so far as JSON.
    Stats(PathBuf),
    /// Close the window (status 0).
    Quit,
}

/// Reads and checks a script: every action is known and well formed, or the error names its
/// index. Relative paths are taken from the current directory, as the CLI's are.
///
/// # Errors
/// The file cannot be read, is not a JSON list, or an action is malformed.
pub fn read(path: &Path) -> Result<Vec<Action>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the script {}", path.display()))?;
    let value: Value =
        serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let Value::Array(items) = value else {
        bail!("{}: a script is a JSON list of actions", path.display());
    };
    items
        .iter()
        .enumerate()
        .map(|(i, item)| parse(item).with_context(|| format!("{}: action {i}", path.display())))
        .collect()
}

fn vec3(v: Option<&Value>, name: &str) -> Result<[f64; 3]> {
    let Some(Value::Array(a)) = v else {
        bail!("`{name}` must be [x, y, z]");
    };
    let xs: Vec<f64> = a.iter().filter_map(Value::as_f64).collect();
    match xs.as_slice() {
        [x, y, z] if xs.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
        _ => bail!(
            "`{name}` must be three finite numbers, got {}",
            Value::Array(a.clone())
        ),
    }
}

fn number(v: &Value, name: &str) -> Result<f64> {
    v.as_f64()
        .filter(|x| x.is_finite())
        .with_context(|| format!("`{name}` must be a finite number, got {v}"))
}

fn path(v: &Value, name: &str) -> Result<PathBuf> {
    v.as_str()
        .map(PathBuf::from)
        .with_context(|| format!("`{name}` must be a file path, got {v}"))
}

/// One action from its JSON object.
fn parse(item: &Value) -> Result<Action> {
    let Value::Object(map) = item else {
        bail!("an action is an object, got {item}");
    };
    let key = map
        .keys()
        .find(|k| *k != "face_ids" && *k != "overlay")
        .with_context(|| format!("an empty action {item}"))?;
    let v = &map[key];
    Ok(match key.as_str() {
        "wait" => {
            let n = number(v, "wait")?;
            if !(0.0..=1e7).contains(&n) {
                bail!("`wait` must be 0 to 10 000 000 frames, got {n}");
            }
            Action::Wait(n as u32)
        }
        "camera" => Action::Camera {
            eye: vec3(v.get("eye"), "eye")?,
            target: vec3(v.get("target"), "target")?,
            up: vec3(v.get("up"), "up")?,
            fov: v.get("fov").map(|f| number(f, "fov")).transpose()?,
        },
        "orbit" => {
            let [dx, dy] = match v.as_array().map(|a| a.as_slice()) {
                Some([a, b]) => [number(a, "orbit")?, number(b, "orbit")?],
                _ => bail!("`orbit` must be [dx_degrees, dy_degrees], got {v}"),
            };
            Action::Orbit(dx, dy)
        }
        "zoom" => {
            let f = number(v, "zoom")?;
            if f <= 0.0 {
                bail!("`zoom` must be a positive factor, got {f}");
            }
            Action::Zoom(f)
        }
        "key" => Action::Key(
            v.as_str()
                .with_context(|| format!("`key` must be a key name, got {v}"))?
                .to_string(),
        ),
        "until_idle" => Action::UntilIdle,
        "screenshot" => Action::Screenshot {
            color: path(v, "screenshot")?,
            face_ids: map
                .get("face_ids")
                .map(|p| path(p, "face_ids"))
                .transpose()?,
            overlay: match map.get("overlay") {
                None => false,
                Some(Value::Bool(b)) => *b,
                Some(other) => bail!("`overlay` must be true or false, got {other}"),
            },
        },
        "stats" => Action::Stats(path(v, "stats")?),
        "quit" => Action::Quit,
        other => bail!(
            "unknown action `{other}` (wait, camera, orbit, zoom, key, until_idle, screenshot, \
             stats, quit)"
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(text: &str) -> Result<Action> {
        parse(&serde_json::from_str(text).unwrap())
    }

    #[test]
    fn every_action_parses_and_bad_ones_are_named() {
        assert_eq!(one(r#"{"wait": 3}"#).unwrap(), Action::Wait(3));
        assert_eq!(
            one(r#"{"orbit": [10, -5]}"#).unwrap(),
            Action::Orbit(10.0, -5.0)
        );
        assert_eq!(
            one(r#"{"screenshot": "a.png", "face_ids": "b.png"}"#).unwrap(),
            Action::Screenshot {
                color: "a.png".into(),
                face_ids: Some("b.png".into()),
                overlay: false
            }
        );
        let c = one(r#"{"camera": {"eye": [0,0,5], "target": [0,0,0], "up": [0,1,0]}}"#);
        assert!(matches!(c.unwrap(), Action::Camera { fov: None, .. }));
        let e = one(r#"{"zoom": -1}"#).unwrap_err().to_string();
        assert!(e.contains("zoom"), "{e}");
        let e = one(r#"{"fly": 1}"#).unwrap_err().to_string();
        assert!(e.contains("unknown action `fly`"), "{e}");
        let e = one(r#"{"camera": {"eye": [0, 0], "target": [0,0,0], "up": [0,1,0]}}"#);
        assert!(e.unwrap_err().to_string().contains("eye"));
    }
}
