//! Every ICC profile `fit --icc` makes (each model `fit --model` knows, ICC versions 4 and
//! 2.4) read by LittleCMS and saved again, as a program that re-embeds a profile does
//! (Pillow's `ImageCmsProfile(path).tobytes()`): every tag is read (`cmsReadTag`), so the
//! save re-encodes them, then `cmsSaveProfileToMem` sizes and writes the profile. The
//! re-saved profile must then give the values the original gives, through `transicc`
//! (forward RGB → PCS XYZ and inverse PCS XYZ → RGB, relative colorimetric).
//!
//! LittleCMS is reached through Python's ctypes on the system's liblcms2. Without python3,
//! liblcms2 or `transicc` the test prints "skipped" and passes, unless
//! `METAMER_ORACLES=required` (CI sets it), when it fails.

use std::path::Path;
use std::process::Command;

use metamer::display::icc::{encode_icc, IccVersion};
use metamer::display::{fit_profile, read_measurement_file, ModelKind};

use crate::icc_readers::{transicc, transicc_installed};
use crate::support::{fresh_dir, text};

/// Reads every tag of each `SRC` and saves the profile to `DST`; exit 3 when LittleCMS
/// cannot be loaded, 1 with the reason when a profile cannot be saved.
const RESAVE: &str = r#"
import ctypes, ctypes.util, sys
try:
    lcms = ctypes.CDLL(ctypes.util.find_library("lcms2") or "liblcms2.so.2")
except OSError as e:
    print("liblcms2 cannot be loaded: %s" % e)
    sys.exit(3)
P, U32 = ctypes.c_void_p, ctypes.c_uint32
lcms.cmsOpenProfileFromFile.restype = P
lcms.cmsOpenProfileFromFile.argtypes = [ctypes.c_char_p, ctypes.c_char_p]
lcms.cmsGetTagCount.argtypes = [P]
lcms.cmsGetTagSignature.argtypes = [P, U32]
lcms.cmsGetTagSignature.restype = U32
lcms.cmsReadTag.argtypes = [P, U32]
lcms.cmsReadTag.restype = P
lcms.cmsSaveProfileToMem.argtypes = [P, P, ctypes.POINTER(U32)]
lcms.cmsCloseProfile.argtypes = [P]
args = sys.argv[1:]
for src, dst in zip(args[::2], args[1::2]):
    h = lcms.cmsOpenProfileFromFile(src.encode(), b"r")
    if not h:
        print("%s: LittleCMS cannot open it" % src)
        sys.exit(1)
    for i in range(lcms.cmsGetTagCount(h)):
        sig = lcms.cmsGetTagSignature(h, i)
        if not lcms.cmsReadTag(h, sig):
            print("%s: LittleCMS cannot read tag %r" % (src, sig.to_bytes(4, "big")))
            sys.exit(1)
    size = U32(0)
    if not lcms.cmsSaveProfileToMem(h, None, ctypes.byref(size)):
        print("%s: LittleCMS cannot determine the profile's size to save it" % src)
        sys.exit(1)
    buf = ctypes.create_string_buffer(size.value)
    if not lcms.cmsSaveProfileToMem(h, buf, ctypes.byref(size)):
        print("%s: LittleCMS cannot save it" % src)
        sys.exit(1)
    open(dst, "wb").write(buf.raw[: size.value])
    lcms.cmsCloseProfile(h)
"#;

/// Whether the oracle is missing: fails under `METAMER_ORACLES=required`, else says why.
fn missing(why: &str) -> bool {
    assert!(
        std::env::var("METAMER_ORACLES").as_deref() != Ok("required"),
        "METAMER_ORACLES=required but {why}"
    );
    eprintln!("skipped: {why}");
    true
}

#[test]
fn littlecms_re_saves_every_profile_fit_makes_and_computes_the_same_values() {
    if !transicc_installed() && missing("LittleCMS `transicc` is not installed") {
        return;
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dispread_analytic.ti3");
    let m = read_measurement_file(&path).unwrap();
    let dir = fresh_dir("icc-resave");
    let mut pairs = Vec::new();
    for kind in ModelKind::ALL {
        let profile = fit_profile(kind, &m.patches, Some(&path))
            .unwrap_or_else(|e| panic!("{kind} does not fit {}: {e}", path.display()));
        for version in [IccVersion::V4, IccVersion::V2_4] {
            let icc = encode_icc(&profile, version, "metamer re-save test").unwrap();
            let original = dir.join(format!("{kind}-{version}.icc"));
            std::fs::write(&original, &icc.bytes).unwrap();
            pairs.push((original, dir.join(format!("{kind}-{version}.resaved.icc"))));
        }
    }
    let out = match Command::new("python3")
        .args(["-c", RESAVE])
        .args(pairs.iter().flat_map(|(a, b)| [a, b]))
        .output()
    {
        Ok(o) => o,
        Err(e) => {
            missing(&format!("python3 cannot be run: {e}"));
            return;
        }
    };
    if out.status.code() == Some(3) {
        missing(text(&out.stdout).trim());
        return;
    }
    assert!(
        out.status.success(),
        "{}{}",
        text(&out.stdout),
        text(&out.stderr)
    );
    // Drive values on a 5-level grid and PCS XYZ of grey to white, both inside and at the
    // edge of every model's range.
    let levels = [0.0, 64.0, 128.0, 192.0, 255.0];
    let rgb: Vec<[f64; 3]> = levels
        .iter()
        .flat_map(|&r| levels.iter().flat_map(move |&g| levels.map(|b| [r, g, b])))
        .collect();
    let xyz: Vec<[f64; 3]> = [5.0, 20.0, 50.0, 90.0]
        .iter()
        .map(|&y| [0.9642 * y, y, 0.8249 * y])
        .collect();
    for (original, resaved) in &pairs {
        let (a, b) = (original.to_str().unwrap(), resaved.to_str().unwrap());
        for (input, from_to) in [
            (&rgb, [["-i", a, "-o", "*XYZ"], ["-i", b, "-o", "*XYZ"]]),
            (&xyz, [["-i", "*XYZ", "-o", a], ["-i", "*XYZ", "-o", b]]),
        ] {
            let before = transicc(&from_to[0], input);
            let after = transicc(&from_to[1], input);
            for ((x, p), q) in input.iter().zip(&before).zip(&after) {
                for c in 0..3 {
                    assert!(
                        (p[c] - q[c]).abs() <= 1e-9,
                        "{}: {x:?} gives {p:?}, re-saved {q:?}",
                        resaved.display()
                    );
                }
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
