//! Reads the scene file from a JSON value field by field, so that a bad field is reported
//! by its JSON path (`surfaces[3].reflectance.outside`) with the shapes that are accepted,
//! rather than by serde's line and column inside an untagged enum.

use metamer_color::text::{echo, echo_message, strip_bom};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Deserializer};
use serde_json::{Map, Value};

use super::file::{
    CameraFile, DistributionFile, EmitterFile, MeterFile, SceneFile, SpectrumRef, SurfaceFile,
    TileFile,
};
use crate::light::CGammaTable;

/// A field of the scene file that is not what the format allows. Shown with the path and
/// message cut to a readable length: both may quote the file (a key, a file name, a value).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}: {}", echo(path), echo_message(message))]
pub struct PathError {
    /// JSON path of the field, e.g. `emitters[0].tiles[3].gain`.
    pub path: String,
    pub message: String,
}

fn err<T>(path: &str, message: impl Into<String>) -> Result<T, PathError> {
    Err(PathError {
        path: path.to_string(),
        message: message.into(),
    })
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "an array",
        Value::Object(_) => "an object",
    }
}

/// A leaf value through serde, its error prefixed with the path.
/// A C-γ table as written, before its own checks.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTable {
    c_deg: Vec<f64>,
    gamma_deg: Vec<f64>,
    values: Vec<Vec<f64>>,
}

fn leaf<T: DeserializeOwned>(path: &str, v: &Value, shape: &str) -> Result<T, PathError> {
    T::deserialize(v).map_err(|e| PathError {
        path: path.to_string(),
        message: format!("expected {shape}, got {} ({e})", kind(v)),
    })
}

/// An object being read: its fields are taken one by one, and whatever is left over is an
/// unknown field.
struct Obj<'a> {
    path: String,
    map: &'a Map<String, Value>,
    known: &'static [&'static str],
}

impl<'a> Obj<'a> {
    fn new(path: &str, v: &'a Value, known: &'static [&'static str]) -> Result<Self, PathError> {
        match v {
            Value::Object(map) => {
                if let Some(k) = map.keys().find(|k| !known.contains(&k.as_str())) {
                    let at = if path.is_empty() {
                        k.clone()
                    } else {
                        format!("{path}.{k}")
                    };
                    return err(
                        &at,
                        format!("unknown field; expected one of: {}", known.join(", ")),
                    );
                }
                Ok(Obj {
                    path: path.to_string(),
                    map,
                    known,
                })
            }
            other => err(
                if path.is_empty() { "(top level)" } else { path },
                format!(
                    "expected an object with fields {}, got {}",
                    known.join(", "),
                    kind(other)
                ),
            ),
        }
    }

    fn at(&self, name: &str) -> String {
        debug_assert!(self.known.contains(&name));
        if self.path.is_empty() {
            name.to_string()
        } else {
            format!("{}.{name}", self.path)
        }
    }

    fn get(&self, name: &str) -> Option<&'a Value> {
        self.map.get(name).filter(|v| !v.is_null())
    }

    fn req<T>(
        &self,
        name: &str,
        read: impl FnOnce(&str, &'a Value) -> Result<T, PathError>,
    ) -> Result<T, PathError> {
        let p = self.at(name);
        match self.get(name) {
            Some(v) => read(&p, v),
            None => err(&p, "missing"),
        }
    }

    fn opt<T>(
        &self,
        name: &str,
        read: impl FnOnce(&str, &'a Value) -> Result<T, PathError>,
    ) -> Result<Option<T>, PathError> {
        let p = self.at(name);
        self.get(name).map(|v| read(&p, v)).transpose()
    }
}

fn number(p: &str, v: &Value) -> Result<f64, PathError> {
    leaf(p, v, "a number")
}

fn count(p: &str, v: &Value) -> Result<usize, PathError> {
    leaf(p, v, "a whole number ≥ 0")
}

fn text(p: &str, v: &Value) -> Result<String, PathError> {
    leaf(p, v, "a string")
}

fn triple(p: &str, v: &Value) -> Result<[f64; 3], PathError> {
    leaf(p, v, "an array of three numbers [x, y, z]")
}

fn list<'a, T>(
    p: &str,
    v: &'a Value,
    read: impl Fn(&str, &'a Value) -> Result<T, PathError>,
) -> Result<Vec<T>, PathError> {
    match v {
        Value::Array(items) => items
            .iter()
            .enumerate()
            .map(|(i, x)| read(&format!("{p}[{i}]"), x))
            .collect(),
        other => err(p, format!("expected an array, got {}", kind(other))),
    }
}

const SPECTRUM_SHAPES: &str = "a number (the same at every wavelength), \
    {\"file\": \"…csv\", \"column\"?: n, \"outside\"?: \"zero\"|\"hold_ends\"} or \
    {\"nm\": […], \"values\": […], \"outside\"?: \"zero\"|\"hold_ends\"}";

pub fn spectrum(p: &str, v: &Value) -> Result<SpectrumRef, PathError> {
    match v {
        Value::Number(_) => Ok(SpectrumRef::Constant(number(p, v)?)),
        Value::Object(m) if m.contains_key("file") => {
            let o = Obj::new(p, v, &["file", "column", "outside"])?;
            Ok(SpectrumRef::File {
                file: o.req("file", text)?,
                column: o.opt("column", count)?,
                outside: o.opt("outside", |p, v| leaf(p, v, "\"zero\" or \"hold_ends\""))?,
            })
        }
        Value::Object(m) if m.contains_key("nm") || m.contains_key("values") => {
            let o = Obj::new(p, v, &["nm", "values", "outside"])?;
            Ok(SpectrumRef::Inline {
                nm: o.req("nm", |p, v| leaf(p, v, "an array of wavelengths (nm)"))?,
                values: o.req("values", |p, v| leaf(p, v, "an array of numbers"))?,
                outside: o.opt("outside", |p, v| leaf(p, v, "\"zero\" or \"hold_ends\""))?,
            })
        }
        other => err(
            p,
            format!(
                "expected a spectrum: {SPECTRUM_SHAPES}; got {}",
                kind(other)
            ),
        ),
    }
}

fn surface(p: &str, v: &Value) -> Result<SurfaceFile, PathError> {
    let o = Obj::new(
        p,
        v,
        &["name", "corner", "edge_u", "edge_v", "reflectance", "patch"],
    )?;
    Ok(SurfaceFile {
        name: o.req("name", text)?,
        corner: o.req("corner", triple)?,
        edge_u: o.req("edge_u", triple)?,
        edge_v: o.req("edge_v", triple)?,
        reflectance: o.req("reflectance", spectrum)?,
        patch: o.opt("patch", count)?,
    })
}

const DISTRIBUTION_SHAPES: &str = "{\"kind\": \"lambertian\"}, \
    {\"kind\": \"cos_power\", \"exponent\": m}, \
    {\"kind\": \"c_gamma\", \"table\": {\"c_deg\": […], \"gamma_deg\": […], \"values\": [[…]…]}}, \
    {\"kind\": \"ies\", \"file\": \"light.ies\"} or {\"kind\": \"ldt\", \"file\": \"light.ldt\"}";

fn distribution(p: &str, v: &Value) -> Result<DistributionFile, PathError> {
    let k = match v.get("kind") {
        Some(Value::String(s)) => s.as_str(),
        _ => return err(p, format!("expected {DISTRIBUTION_SHAPES}")),
    };
    match k {
        "lambertian" => {
            Obj::new(p, v, &["kind"])?;
            Ok(DistributionFile::Lambertian)
        }
        "cos_power" => {
            let o = Obj::new(p, v, &["kind", "exponent"])?;
            Ok(DistributionFile::CosPower {
                exponent: o.req("exponent", number)?,
            })
        }
        "c_gamma" => {
            let o = Obj::new(p, v, &["kind", "table"])?;
            // The shape first, then the table's own checks, so that a bad value is named
            // by its place in the table rather than lost inside a "wrong shape" message.
            let raw: RawTable = o.req("table", |p, v| {
                leaf(
                    p,
                    v,
                    "a C-γ table {\"c_deg\": […], \"gamma_deg\": [0 … 90], \"values\": [[1, …], …]}",
                )
            })?;
            let table =
                CGammaTable::new(raw.c_deg, raw.gamma_deg, raw.values).map_err(|e| PathError {
                    path: format!("{p}.table"),
                    message: e.to_string(),
                })?;
            Ok(DistributionFile::CGamma { table })
        }
        "ies" | "ldt" => {
            let o = Obj::new(p, v, &["kind", "file"])?;
            let file: String = o.req("file", |p, v| leaf(p, v, "a file name"))?;
            Ok(if k == "ies" {
                DistributionFile::Ies { file }
            } else {
                DistributionFile::Ldt { file }
            })
        }
        other => err(
            &format!("{p}.kind"),
            format!("unknown kind \"{other}\"; expected {DISTRIBUTION_SHAPES}"),
        ),
    }
}

fn tile(p: &str, v: &Value) -> Result<TileFile, PathError> {
    let o = Obj::new(p, v, &["row", "col", "gain", "spectrum"])?;
    Ok(TileFile {
        row: o.req("row", count)?,
        col: o.req("col", count)?,
        gain: o.opt("gain", number)?.unwrap_or(1.0),
        spectrum: o.opt("spectrum", spectrum)?,
    })
}

fn emitter(p: &str, v: &Value) -> Result<EmitterFile, PathError> {
    let o = Obj::new(
        p,
        v,
        &[
            "corner",
            "edge_u",
            "edge_v",
            "rows",
            "cols",
            "tiles",
            "spectrum",
            "luminance_cd_m2",
            "distribution",
            "reflectance",
        ],
    )?;
    Ok(EmitterFile {
        corner: o.req("corner", triple)?,
        edge_u: o.req("edge_u", triple)?,
        edge_v: o.req("edge_v", triple)?,
        rows: o.opt("rows", count)?.unwrap_or(1),
        cols: o.opt("cols", count)?.unwrap_or(1),
        tiles: o.opt("tiles", |p, v| list(p, v, tile))?.unwrap_or_default(),
        spectrum: o.opt("spectrum", spectrum)?,
        luminance_cd_m2: o.opt("luminance_cd_m2", number)?,
        distribution: o.opt("distribution", distribution)?.unwrap_or_default(),
        reflectance: o.opt("reflectance", spectrum)?,
    })
}

fn camera(p: &str, v: &Value) -> Result<CameraFile, PathError> {
    let o = Obj::new(
        p,
        v,
        &["position", "look_at", "up", "vfov_deg", "width", "height"],
    )?;
    Ok(CameraFile {
        position: o.req("position", triple)?,
        look_at: o.req("look_at", triple)?,
        up: o.req("up", triple)?,
        vfov_deg: o.req("vfov_deg", number)?,
        width: o.req("width", count)?,
        height: o.req("height", count)?,
    })
}

fn meter(p: &str, v: &Value) -> Result<MeterFile, PathError> {
    let o = Obj::new(p, v, &["acceptance_deg"])?;
    Ok(MeterFile {
        acceptance_deg: o.req("acceptance_deg", number)?,
    })
}

/// The whole file.
pub fn scene(v: &Value) -> Result<SceneFile, PathError> {
    let o = Obj::new(
        "",
        v,
        &[
            "name",
            "description",
            "provenance",
            "surfaces",
            "emitters",
            "camera",
            "meter",
        ],
    )?;
    Ok(SceneFile {
        name: o.req("name", text)?,
        description: o.opt("description", text)?,
        provenance: o.opt("provenance", |p, v| match v {
            Value::Object(m) => Ok(m.clone()),
            other => err(p, format!("expected an object, got {}", kind(other))),
        })?,
        surfaces: o.req("surfaces", |p, v| list(p, v, surface))?,
        emitters: o.req("emitters", |p, v| list(p, v, emitter))?,
        camera: o.opt("camera", camera)?,
        meter: o.opt("meter", meter)?,
    })
}

// Parsing is this file's job, so the file types' JSON entry points live here.
impl SceneFile {
    /// Parses scene JSON (a UTF-8 byte-order mark, as some editors save, is skipped);
    /// errors name the JSON path of the bad field.
    pub fn from_json(text: &str) -> Result<SceneFile, PathError> {
        let v: serde_json::Value =
            serde_json::from_str(strip_bom(text)).map_err(|e| PathError {
                path: format!("line {} column {}", e.line(), e.column()),
                message: format!("not JSON: {e}"),
            })?;
        scene(&v)
    }
}

impl<'de> Deserialize<'de> for SceneFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = serde_json::Value::deserialize(d)?;
        scene(&v).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn minimal() -> Value {
        json!({
            "name": "t",
            "surfaces": [{"name": "floor", "corner": [0, 0, 0], "edge_u": [1, 0, 0],
                          "edge_v": [0, 0, 1], "reflectance": 0.5}],
            "emitters": [{"corner": [0, 1, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1],
                          "luminance_cd_m2": 100}]
        })
    }

    #[test]
    fn a_bad_outside_is_named_by_its_path() {
        let mut v = minimal();
        v["surfaces"][0]["reflectance"] = json!({"file": "x.csv", "outside": "clamp"});
        let e = scene(&v).unwrap_err();
        assert_eq!(e.path, "surfaces[0].reflectance.outside");
        assert!(e.message.contains("hold_ends"), "{}", e.message);
    }

    #[test]
    fn a_spectrum_of_the_wrong_shape_lists_the_shapes() {
        let mut v = minimal();
        v["surfaces"][0]["reflectance"] = json!("grey");
        let e = scene(&v).unwrap_err();
        assert_eq!(e.path, "surfaces[0].reflectance");
        assert!(e.message.contains("\"file\""), "{}", e.message);
    }

    #[test]
    fn unknown_and_missing_fields_are_named() {
        let mut v = minimal();
        v["emitters"][0]["gian"] = json!(1);
        assert_eq!(scene(&v).unwrap_err().path, "emitters[0].gian");
        let mut v = minimal();
        v["surfaces"][0].as_object_mut().unwrap().remove("corner");
        let e = scene(&v).unwrap_err();
        assert_eq!(
            (e.path.as_str(), e.message.as_str()),
            ("surfaces[0].corner", "missing")
        );
        let mut v = minimal();
        v["emitters"][0]["distribution"] = json!({"kind": "c_gamma", "table": {"c_deg": [0]}});
        assert_eq!(
            scene(&v).unwrap_err().path,
            "emitters[0].distribution.table"
        );
    }
}
