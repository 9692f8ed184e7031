//! The C ABI: the header agrees with the code, the C example (built with the system compiler
//! against the static library) gives the Rust result, and no entry point crashes on null
//! pointers, wrong lengths, or truncated, foreign, hostile or missing files.

mod support;

use std::collections::BTreeMap;
use std::ffi::{c_int, CStr, CString};
use std::ptr::{null, null_mut};

use pvt3_runtime::ffi::*;
use pvt3_runtime::{read_npy, Classifier};
use support::{golden, root, scratch, streamed_windows, target_cc, target_command};

/// Removes `/* … */` comments and folds white space.
fn strip_c_comments(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(start) = rest.find("/*") {
        out.push_str(&rest[..start]);
        rest = rest[start..].split_once("*/").map_or("", |(_, after)| after);
    }
    out.push_str(rest);
    out.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Tokens of a C type, `*` apart: `const char **` → `const char * *`.
fn c_tokens(text: &str) -> String {
    text.replace('*', " * ").split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The C spelling of a Rust type of the ABI: `*mut *const c_char` → `const char * *`.
fn c_type(rust: &str) -> String {
    let rust = rust.trim();
    if let Some(inner) = rust.strip_prefix("*const ") {
        let inner = c_type(inner);
        return if inner.ends_with('*') { format!("{inner} const *") } else { format!("const {inner} *") };
    }
    if let Some(inner) = rust.strip_prefix("*mut ") {
        return format!("{} *", c_type(inner));
    }
    match rust {
        "c_int" => "int",
        "usize" => "size_t",
        "f32" => "float",
        "f64" => "double",
        "u8" => "unsigned char",
        "u64" => "uint64_t",
        "c_char" => "char",
        "Pvt3Classifier" => "pvt3_classifier",
        "Pvt3Session" => "pvt3_session",
        "Pvt3Continuous" => "pvt3_continuous",
        "" | "()" => "void",
        other => panic!("a Rust type the ABI test does not map to C: {other}"),
    }
    .to_string()
}

/// `name → (return type, parameter types)` of a C declaration `ret name(type name, …)`.
fn c_signature(decl: &str) -> Option<(String, (String, Vec<String>))> {
    let (head, tail) = decl.split_once('(')?;
    let head = c_tokens(head);
    let (ret, name) = head.rsplit_once(' ')?;
    let params = tail.rsplit_once(')')?.0.trim();
    // Each parameter without its name (the last word).
    let types = params
        .split(',')
        .map(c_tokens)
        .filter(|p| !p.is_empty() && p != "void")
        .map(|p| p.rsplit_once(' ').map_or(p.clone(), |(t, _)| t.to_string()))
        .collect();
    Some((name.to_string(), (ret.to_string(), types)))
}

/// The same, of a Rust definition `name(p: T, …) -> R` given from its name on.
fn rust_signature(def: &str) -> Option<(String, (String, Vec<String>))> {
    let (name, tail) = def.split_once('(')?;
    let (params, after) = tail.split_once(')')?;
    let ret = after.split('{').next()?.trim().strip_prefix("-> ").unwrap_or("");
    let types = params.split(',').filter(|p| !p.trim().is_empty()).map(|p| c_tokens(&c_type(p.split_once(':').map_or("", |(_, t)| t))));
    Some((name.trim().to_string(), (c_tokens(&c_type(ret)), types.collect())))
}

#[test]
fn the_header_declares_exactly_what_the_code_exports() {
    let header = strip_c_comments(&std::fs::read_to_string(root().join("include/pvt3.h")).unwrap());
    let code = std::fs::read_to_string(root().join("src/ffi.rs")).unwrap();
    let header_fns: BTreeMap<_, _> = header
        .split(';')
        .filter(|d| d.contains("pvt3_") && d.contains('('))
        .filter_map(|d| c_signature(d.split("#define").last()?))
        .collect();
    let code_fns: BTreeMap<_, _> = code.split("extern \"C\" fn ").skip(1).filter_map(rust_signature).collect();
    assert_eq!(header_fns, code_fns, "functions, their return and parameter types");
    assert_eq!(code_fns.len(), 40);
    assert_eq!(code_fns["pvt3_classify"].1[6], "size_t *", "the types are read");
    let mut header_consts: Vec<(String, String)> = header
        .split("#define ")
        .skip(1)
        .filter_map(|d| {
            let mut w = d.split(' ');
            let name = w.next()?;
            name.starts_with("PVT3_").then(|| Some((name.to_string(), w.next()?.to_string())))?
        })
        .filter(|(n, _)| n != "PVT3_H")
        .collect();
    // The status enum's members, `PVT3_OK = 0, …`.
    let statuses = header.split("typedef enum pvt3_status {").nth(1).and_then(|e| e.split('}').next()).expect("the status enum");
    header_consts.extend(statuses.split(',').filter_map(|m| {
        let (name, value) = m.split_once('=')?;
        Some((name.trim().to_string(), value.trim().to_string()))
    }));
    let mut code_consts: Vec<(String, String)> = code
        .lines()
        .filter_map(|l| l.strip_prefix("pub const "))
        .filter_map(|l| Some((l.split(':').next()?.to_string(), l.split("= ").nth(1)?.trim_end_matches(';').to_string())))
        .collect();
    header_consts.sort();
    code_consts.sort();
    assert_eq!(header_consts, code_consts, "status codes, kernel choices, versions");
    assert_eq!(header_consts.iter().filter(|(n, _)| n.starts_with("PVT3_ERR_") || n == "PVT3_OK").count(), 6);
}

/// Each function the header declares follows a comment that says what it does.
#[test]
fn every_function_in_the_header_is_documented() {
    let header = std::fs::read_to_string(root().join("include/pvt3.h")).unwrap();
    let code = std::fs::read_to_string(root().join("src/ffi.rs")).unwrap();
    let lines: Vec<&str> = header.lines().collect();
    let undocumented: Vec<String> = code
        .split("extern \"C\" fn ")
        .skip(1)
        .filter_map(|def| def.split_once('(').map(|(name, _)| name.trim().to_string()))
        .filter(|name| {
            let in_comment = |l: &str| l.trim_start().starts_with("/*") || l.trim_start().starts_with('*');
            let declared = |l: &&str| l.contains(&format!("{name}(")) && !in_comment(l);
            let at = lines.iter().position(declared).unwrap_or_else(|| panic!("{name} is not declared"));
            !lines[..at].iter().rev().find(|l| !l.trim().is_empty()).is_some_and(|l| l.trim_end().ends_with("*/"))
        })
        .collect();
    assert!(undocumented.is_empty(), "declared without a comment before them: {undocumented:?}");
}

/// The version macros are the crate's version and the format's, as `pvt3_version()` says them.
#[test]
fn the_version_macros_are_the_crate_s_and_the_format_s() {
    let crate_version = [env!("CARGO_PKG_VERSION_MAJOR"), env!("CARGO_PKG_VERSION_MINOR"), env!("CARGO_PKG_VERSION_PATCH")];
    let macros = [PVT3_VERSION_MAJOR, PVT3_VERSION_MINOR, PVT3_VERSION_PATCH].map(|v| v.to_string());
    assert_eq!(macros, crate_version);
    let (major, minor) = pvt3_format::FORMAT_VERSION;
    assert_eq!((PVT3_FORMAT_MAJOR, PVT3_FORMAT_MINOR), (major as c_int, minor as c_int));
    let said = unsafe { CStr::from_ptr(pvt3_version()) }.to_str().unwrap().to_string();
    assert_eq!(said, format!("{PVT3_VERSION_MAJOR}.{PVT3_VERSION_MINOR}.{PVT3_VERSION_PATCH} (format {major}.{minor})"));
}

/// The camera example (`examples/camera.c`, built as `exe`) on a touch of bytes: the golden
/// model's answer to a session given the same bytes.
fn camera_example_answers_as_a_session(exe: &std::path::Path, dir: &std::path::Path) {
    let touch: Vec<u8> = (0..75 * 60).map(|i| (i * 13 % 251) as u8).collect();
    let path = dir.join("touch.u8");
    std::fs::write(&path, &touch).unwrap();
    let out = target_command(exe).arg(golden("model.onnx")).arg(&path).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let mut session = c.session().unwrap();
    touch.chunks(60).for_each(|frame| session.push_camera_frame(frame).unwrap());
    let expected = session.finish().unwrap();
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 2, "{stdout}");
    for (line, way) in stdout.lines().zip(["camera", "whole"]) {
        let fields: Vec<&str> = line.split('\t').collect();
        assert_eq!((fields[0], fields[1].parse::<usize>().unwrap(), fields[2]), (way, expected.class, expected.label.as_str()), "{line}");
        let probs: Vec<f32> = fields[4..].iter().map(|v| v.parse().unwrap()).collect();
        assert!(probs.iter().zip(&expected.probabilities).all(|(a, b)| (a - b).abs() < 1e-6), "{line}");
    }
}

/// The guide's two lines that build a C program against the installed library (docs/guide/robot.md,
/// "From C"): the static one, then the shared one, as written.
fn guide_c_lines() -> [String; 2] {
    let guide = std::fs::read_to_string(root().join("../docs/guide/robot.md")).unwrap();
    let lines: Vec<String> =
        guide.lines().filter(|l| l.starts_with("cc app.c ")).map(|l| l.split("  #").next().unwrap().trim().to_string()).collect();
    let line = |needle: &str| {
        lines.iter().find(|l| l.contains(needle)).unwrap_or_else(|| panic!("the guide has no `{needle}` line: {lines:?}")).clone()
    };
    [line("--libs pvt3-static)"), line("--libs pvt3)")]
}

/// Runs a guide's `cc app.c … -o app` line on `source`, writing `exe`, with the target's compiler
/// and the libraries installed under `prefix`.
fn build_as_the_guide_says(line: &str, source: &std::path::Path, exe: &std::path::Path, prefix: &std::path::Path) {
    let script = line.replacen("cc app.c", r#""$CC" "$SOURCE""#, 1).replace(" -o app", r#" -o "$EXE""#);
    let cc = std::process::Command::new("sh")
        .args(["-c", &script])
        .env("CC", target_cc())
        .env("SOURCE", source)
        .env("EXE", exe)
        .env("PKG_CONFIG_PATH", prefix.join("lib/pkgconfig"))
        .output()
        .expect("sh runs");
    assert!(cc.status.success(), "{line} ({}) failed:\n{}", source.display(), String::from_utf8_lossy(&cc.stderr));
}

#[test]
fn the_c_example_gives_the_rust_result() {
    let dir = scratch("example");
    let exe = dir.join("classify");
    // The test binary lives in target/<profile>/deps; the static library in target/<profile>/examples.
    let profile_dir = std::env::current_exe().unwrap().parent().unwrap().parent().unwrap().to_path_buf();
    let built = dir.join("built");
    std::fs::create_dir_all(&built).unwrap();
    std::fs::copy(profile_dir.join("examples/libpvt3_c.a"), built.join("libpvt3_runtime.a")).unwrap();
    // The shared library beside it, where the target builds one (musl's builds none).
    let shared = profile_dir.join("examples/libpvt3_c.so");
    if shared.exists() {
        std::fs::copy(&shared, built.join("libpvt3_runtime.so")).unwrap();
    }
    // Installed as a robot's build finds it (runtime/install.sh), and built by the guide's lines.
    let prefix = dir.join("prefix");
    let install = std::process::Command::new("bash")
        .arg(root().join("install.sh"))
        .arg(&prefix)
        .env("PVT3_LIB_DIR", &built)
        .output()
        .expect("bash runs runtime/install.sh");
    assert!(install.status.success(), "install.sh failed:\n{}", String::from_utf8_lossy(&install.stderr));
    let pc = std::fs::read_to_string(prefix.join("lib/pkgconfig/pvt3.pc")).unwrap();
    assert!(pc.contains(&format!("\nVersion: {}\n", env!("CARGO_PKG_VERSION"))), "{pc}");
    let [static_line, shared_line] = guide_c_lines();
    let shared_classify = dir.join("classify-shared");
    for (line, source, exe) in [
        (&static_line, "classify.c", &exe),
        (&static_line, "camera.c", &dir.join("camera")),
        (&shared_line, "classify.c", &shared_classify),
    ] {
        build_as_the_guide_says(line, &root().join("examples").join(source), exe, &prefix);
    }
    let needs = |exe: &std::path::Path| {
        let out = std::process::Command::new("readelf").arg("-d").arg(exe).output().expect("readelf runs (binutils)");
        String::from_utf8_lossy(&out.stdout).contains("libpvt3_runtime.so")
    };
    assert!(!needs(&exe), "the static line's program needs the shared library");
    assert_eq!(needs(&shared_classify), shared.exists(), "the shared line's program and the shared library");
    camera_example_answers_as_a_session(&dir.join("camera"), &dir);

    // The example classifies, streams, peeks at and slides over the first `windows` windows.
    let windows = streamed_windows();
    let (_, x) = read_npy(&golden("input.npy")).unwrap();
    let x = &x[..windows * 4500];
    let raw = dir.join("input.f32");
    std::fs::write(&raw, x.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>()).unwrap();
    let out = target_command(&exe).arg(golden("model.onnx")).arg(&raw).arg(windows.to_string()).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let c = Classifier::load(golden("model.onnx")).unwrap();
    let rust = c.classify_batch(x, windows).unwrap();
    // What a session answers halfway through each touch (37 of 75 frames).
    let mut session = c.session().unwrap();
    let halfway: Vec<_> = (0..windows)
        .map(|w| {
            for t in 0..37 {
                session.push_frame(&(0..60).map(|i| x[w * 4500 + i * 75 + t]).collect::<Vec<_>>()).unwrap();
            }
            let peek = session.peek().unwrap().prediction;
            session.reset();
            peek
        })
        .collect();
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 1 + 5 * windows);
    let input = stdout.lines().next().unwrap();
    let shape = c.sample_shape().iter().map(|v| v.to_string()).collect::<Vec<_>>().join("x");
    let format = c.metadata_value(pvt3_format::keys::FORMAT).unwrap();
    let (entries, last) = (c.metadata().len(), &c.metadata().last().unwrap().0);
    assert_eq!(input, format!("input\t{shape}\t{}\t{}\t{format}\t{entries} {last}", c.kept_frames().len(), u8::from(c.streams())));
    let (logits, _) = c.run(x, windows).unwrap();
    for (line, expected) in stdout.lines().filter(|l| l.starts_with("logits")).zip(logits.chunks(c.classes().len())) {
        let values: Vec<f32> = line.split('\t').skip(2).map(|v| v.parse().unwrap()).collect();
        assert!(values.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-5) && values.len() == expected.len(), "{line}");
    }
    // Sliding on over the windows back to back, answering once a window: the windows' own.
    for (way, expected) in [("batch", &rust), ("stream", &rust), ("peek", &halfway), ("slide", &rust)] {
        assert_eq!(stdout.lines().filter(|l| l.starts_with(way)).count(), windows, "{way}");
        for (line, p) in stdout.lines().filter(|l| l.starts_with(way)).zip(expected) {
            let fields: Vec<&str> = line.split('\t').collect();
            assert_eq!(fields[2].parse::<usize>().unwrap(), p.class);
            assert_eq!(fields[3], p.label);
            let probs: Vec<f32> = fields[5..].iter().map(|v| v.parse().unwrap()).collect();
            assert!(probs.iter().zip(&p.probabilities).all(|(a, b)| (a - b).abs() < 1e-5), "{line}");
        }
    }
    // The shared line's program answers as the static one does, found by its run path.
    let shared_out = target_command(&shared_classify).arg(golden("model.onnx")).arg(&raw).arg(windows.to_string()).output().unwrap();
    assert!(shared_out.status.success(), "{}", String::from_utf8_lossy(&shared_out.stderr));
    assert_eq!(String::from_utf8(shared_out.stdout).unwrap(), stdout, "the shared library's answers");
    let bad = target_command(&exe).arg(dir.join("absent.onnx")).arg(&raw).arg("8").output().unwrap();
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("absent.onnx"));
    // Under valgrind (tests/run.sh sets PVT3_VALGRIND on x86-64): the example's way through and
    // its error paths (no such file, too few values) read and write no memory they should not,
    // and leave nothing allocated behind.
    if std::env::var_os("PVT3_VALGRIND").is_some() {
        let short = dir.join("short.f32");
        std::fs::write(&short, &std::fs::read(&raw).unwrap()[..400]).unwrap();
        let cases = [(golden("model.onnx"), &raw, true), (dir.join("absent.onnx"), &raw, false), (golden("model.onnx"), &short, false)];
        for (model, input, succeeds) in cases {
            let out = std::process::Command::new("valgrind")
                .args(["-q", "--error-exitcode=99", "--leak-check=full", "--errors-for-leak-kinds=definite,indirect"])
                .args(["--show-leak-kinds=definite,indirect"])
                .arg(&exe)
                .arg(&model)
                .arg(input)
                .arg("2")
                .output()
                .expect("valgrind runs (apt-get install valgrind)");
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_ne!(out.status.code(), Some(99), "valgrind: {} {}:\n{stderr}", model.display(), input.display());
            assert_eq!(out.status.success(), succeeds, "{stderr}");
        }
        let touch = dir.join("touch.u8");
        let out = std::process::Command::new("valgrind")
            .args(["-q", "--error-exitcode=99", "--leak-check=full", "--errors-for-leak-kinds=definite,indirect"])
            .arg(dir.join("camera"))
            .arg(golden("model.onnx"))
            .arg(&touch)
            .output()
            .expect("valgrind runs");
        assert!(out.status.success(), "valgrind: the camera example:\n{}", String::from_utf8_lossy(&out.stderr));
    }
    std::fs::remove_dir_all(dir).unwrap();
}

fn last_error() -> String {
    unsafe { CStr::from_ptr(pvt3_last_error()) }.to_string_lossy().to_string()
}

#[test]
fn every_entry_point_reports_instead_of_crashing() {
    unsafe {
        let model = CString::new(golden("model.onnx").to_str().unwrap()).unwrap();
        let mut c = null_mut();
        assert_eq!(pvt3_classifier_load(null(), &mut c), PVT3_ERR_NULL);
        assert!(last_error().contains("path is a null pointer"));
        assert_eq!(pvt3_classifier_load(model.as_ptr(), null_mut()), PVT3_ERR_NULL);
        let mut n = 0usize;
        assert_eq!(pvt3_classifier_sample_len(null(), &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_num_classes(null(), &mut n), PVT3_ERR_NULL);
        let mut name = null();
        assert_eq!(pvt3_classifier_class_name(null(), 0, &mut name, null_mut()), PVT3_ERR_NULL);
        let mut probs = vec![0f32; 40];
        assert_eq!(pvt3_classify(null(), probs.as_ptr(), 1, 1, probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_frames(null(), &mut n), PVT3_ERR_NULL);
        let mut s = null_mut();
        assert_eq!(pvt3_session_new(null(), &mut s), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_push_frame(null_mut(), probs.as_ptr(), 60), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_finish(null_mut(), probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_peek(null_mut(), probs.as_mut_ptr(), 40, null_mut(), null_mut(), null_mut()), PVT3_ERR_NULL);
        pvt3_session_free(null_mut());
        pvt3_classifier_free(null_mut());
        let mut k = null_mut();
        let mut answered = 7;
        assert_eq!(pvt3_classifier_tubelet(null(), &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_continuous_new(null(), 1, &mut k), PVT3_ERR_NULL);
        assert_eq!(
            pvt3_continuous_push_frame(null_mut(), probs.as_ptr(), 60, probs.as_mut_ptr(), 40, null_mut(), &mut answered),
            PVT3_ERR_NULL
        );
        assert_eq!(pvt3_continuous_reset(null_mut()), PVT3_ERR_NULL);
        pvt3_continuous_free(null_mut());

        assert_eq!(pvt3_classifier_set_kernels(null_mut(), PVT3_KERNELS_TRACT), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_set_threads(null_mut(), 2), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_reset(null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_load_bytes(null(), 10, null(), &mut c), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_load_bytes(b"onnx".as_ptr(), 4, null(), null_mut()), PVT3_ERR_NULL);
        for (status, text) in
            [(PVT3_OK, "PVT3_OK: success"), (PVT3_ERR_INPUT, "PVT3_ERR_INPUT: an argument"), (6, "unknown"), (-1, "unknown")]
        {
            let said = CStr::from_ptr(pvt3_status_text(status)).to_str().unwrap();
            assert!(said.starts_with(text), "{status}: {said}");
        }
        assert_eq!(pvt3_classifier_prepare(null(), 1, 1), PVT3_ERR_NULL);
        let mut flag = 0;
        let mut counted = 0u64;
        assert_eq!(pvt3_classifier_input_shape(null(), &mut n, 1, &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_camera_shape(null(), &mut n, &mut n, &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_kept_frames(null(), &mut n, 1, &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_streams(null(), &mut flag), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_metadata_count(null(), &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_metadata_key(null(), 0, &mut name, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_metadata(null(), c"pvt3.format".as_ptr(), &mut name, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classify_logits(null(), probs.as_ptr(), 1, 1, probs.as_mut_ptr(), 40), PVT3_ERR_NULL);
        assert_eq!(pvt3_classify_camera_touches(null(), b"x".as_ptr(), 1, 1, probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_received(null(), &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_continuous_received(null(), &mut counted), PVT3_ERR_NULL);
        let mut written = 0usize;
        assert_eq!(pvt3_read_touch(null(), probs.as_ptr(), 40, 1.0, 1.0, probs.as_mut_ptr(), 40, &mut written), PVT3_ERR_NULL);

        assert_eq!(pvt3_classifier_load(model.as_ptr(), &mut c), PVT3_OK);
        assert_eq!(pvt3_classifier_tubelet(c, &mut n), PVT3_OK);
        assert_eq!(n, 1);
        // A continuous stream: every 0 tokens refused; a frame answers nothing until a window is in.
        assert_eq!(pvt3_continuous_new(c, 0, &mut k), PVT3_ERR_INPUT);
        assert!(last_error().contains("not every 0"), "{}", last_error());
        assert_eq!(pvt3_continuous_new(c, 1, &mut k), PVT3_OK);
        let frame = vec![0.5f32; 60];
        assert_eq!(pvt3_continuous_push_frame(k, frame.as_ptr(), 59, probs.as_mut_ptr(), 40, null_mut(), &mut answered), PVT3_ERR_INPUT);
        assert_eq!(pvt3_continuous_push_frame(k, frame.as_ptr(), 60, probs.as_mut_ptr(), 19, null_mut(), &mut answered), PVT3_ERR_INPUT);
        assert_eq!(pvt3_continuous_push_frame(k, null(), 60, probs.as_mut_ptr(), 40, null_mut(), &mut answered), PVT3_ERR_NULL);
        for t in 0..76 {
            let mut class = 99usize;
            assert_eq!(pvt3_continuous_push_frame(k, frame.as_ptr(), 60, probs.as_mut_ptr(), 40, &mut class, &mut answered), PVT3_OK);
            assert_eq!(answered, c_int::from(t >= 74), "frame {t}");
            assert_eq!(class == 99, t < 74, "frame {t}: a class only with an answer");
        }
        assert_eq!(pvt3_continuous_reset(k), PVT3_OK);
        assert_eq!(pvt3_continuous_push_frame(k, frame.as_ptr(), 60, probs.as_mut_ptr(), 40, null_mut(), &mut answered), PVT3_OK);
        assert_eq!(answered, 0, "a reset stream waits for a whole window");
        pvt3_continuous_free(k);
        assert_eq!(pvt3_classifier_set_kernels(c, 7), PVT3_ERR_INPUT);
        assert!(last_error().contains("kernel choice 7"), "{}", last_error());
        for kernels in [PVT3_KERNELS_TRACT, PVT3_KERNELS_MEASURED, PVT3_KERNELS_FIXED] {
            assert_eq!(pvt3_classifier_set_kernels(c, kernels), PVT3_OK);
        }
        assert_eq!(pvt3_classifier_prepare(c, 0, 0), PVT3_ERR_INPUT);
        assert_eq!(pvt3_classifier_prepare(c, 2, 1), PVT3_OK);
        assert_eq!(pvt3_classifier_sample_len(c, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_input_shape(c, null_mut(), 4, &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_input_shape(c, [0usize; 4].as_mut_ptr(), 4, null_mut()), PVT3_ERR_NULL);
        assert!(last_error().contains("rank is a null pointer"), "{}", last_error());
        assert_eq!(pvt3_classifier_camera_shape(c, &mut n, null_mut(), &mut n), PVT3_ERR_NULL);
        assert!(last_error().contains("width is a null pointer"), "{}", last_error());
        assert_eq!(pvt3_classifier_kept_frames(c, null_mut(), 4, &mut n), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_streams(c, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_metadata_count(c, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_metadata_key(c, 0, null_mut(), null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_metadata(c, null(), &mut name, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_metadata(c, c"pvt3.format".as_ptr(), null_mut(), null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classify_logits(c, [0f32; 4500].as_ptr(), 4500, 1, null_mut(), 20), PVT3_ERR_NULL);
        assert_eq!(pvt3_classify_camera_touches(c, null(), 4500, 1, probs.as_mut_ptr(), 20, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_num_classes(c, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_class_name(c, 0, null_mut(), null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_class_name(c, 20, &mut name, null_mut()), PVT3_ERR_INPUT);
        let mut len = 0usize;
        assert_eq!(pvt3_classifier_class_name(c, 3, &mut name, null_mut()), PVT3_OK);
        assert_eq!(CStr::from_ptr(name).to_str().unwrap(), "material_4");
        assert_eq!(pvt3_classifier_class_name(c, 11, &mut name, &mut len), PVT3_OK);
        assert_eq!((CStr::from_ptr(name).to_str().unwrap(), len), ("material_12", 11));
        let version = CStr::from_ptr(pvt3_version()).to_str().unwrap();
        let (major, minor) = pvt3_format::FORMAT_VERSION;
        assert_eq!(version, format!("{} (format {major}.{minor})", env!("CARGO_PKG_VERSION")));
        // A touch of 80 frames: this model reads frames as recorded, so they come back as they are;
        // too little room says how much is needed.
        let touch: Vec<f32> = (0..60 * 80).map(|v| v as f32).collect();
        let mut read = vec![0f32; touch.len()];
        let mut written = 0usize;
        assert_eq!(pvt3_read_touch(c, null(), 4800, 10.0, 0.0, read.as_mut_ptr(), 4800, &mut written), PVT3_ERR_NULL);
        assert_eq!(pvt3_read_touch(c, touch.as_ptr(), 4800, 10.0, 0.0, null_mut(), 4800, &mut written), PVT3_ERR_NULL);
        assert_eq!(pvt3_read_touch(c, touch.as_ptr(), 4800, 10.0, 0.0, read.as_mut_ptr(), 4800, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_read_touch(c, touch.as_ptr(), 4799, 10.0, 0.0, read.as_mut_ptr(), 4800, &mut written), PVT3_ERR_INPUT);
        assert!(last_error().contains("4799 values are not 60 rows"), "{}", last_error());
        assert_eq!(pvt3_read_touch(c, touch.as_ptr(), 4800, 10.0, 0.0, read.as_mut_ptr(), 4000, &mut written), PVT3_ERR_INPUT);
        assert_eq!(written, 4800, "how much room the touch needs");
        assert_eq!(pvt3_read_touch(c, touch.as_ptr(), 4800, 10.0, 0.0, read.as_mut_ptr(), 4800, &mut written), PVT3_OK);
        assert_eq!((written, &read), (4800, &touch));
        let frames = vec![0.5f32; 2 * 4500];
        assert_eq!(pvt3_classify(c, null(), 4500, 1, probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classify(c, frames.as_ptr(), 4500, 1, null_mut(), 40, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classify(c, frames.as_ptr(), 4499, 1, probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_INPUT);
        assert!(last_error().contains("input has 4499 values; expected 4500"), "{}", last_error());
        // A window of another sensor (BioTac: 19 × 400) for this iCub model.
        assert_eq!(pvt3_classify(c, frames.as_ptr(), 7600, 1, probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_INPUT);
        assert_eq!(pvt3_classify(c, frames.as_ptr(), 9000, 2, probs.as_mut_ptr(), 39, null_mut()), PVT3_ERR_INPUT);
        assert!(last_error().contains("room for 39 values; 40 needed"));
        // batch × classes and batch × sample length overflow: an error, not a wrapped size.
        assert_eq!(pvt3_classify(c, frames.as_ptr(), 9000, usize::MAX / 4, probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_INPUT);
        assert!(last_error().contains("more values than memory can address"), "{}", last_error());
        assert_eq!(
            pvt3_classify(c, frames.as_ptr(), 9000, usize::MAX / 4500 + 1, probs.as_mut_ptr(), usize::MAX, null_mut()),
            PVT3_ERR_INPUT
        );
        assert!(last_error().contains("more values than memory can address"), "{}", last_error());
        let mut nan = frames.clone();
        nan[5] = f32::NAN;
        assert_eq!(pvt3_classify(c, nan.as_ptr(), 4500, 1, probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_INPUT);
        let mut best = [0usize; 2];
        assert_eq!(pvt3_classify(c, frames.as_ptr(), 9000, 2, probs.as_mut_ptr(), 40, best.as_mut_ptr()), PVT3_OK);
        assert!((probs[..20].iter().sum::<f32>() - 1.0).abs() < 1e-5);
        assert_eq!(pvt3_classifier_frames(c, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_frames(c, &mut n), PVT3_OK);
        assert_eq!(n, 75);
        assert_eq!(pvt3_session_new(c, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_new_touch(null(), 50.0, 0.0, &mut s), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_new_touch(c, 50.0, 0.0, null_mut()), PVT3_ERR_NULL);
        // This model reads frames as recorded: a session for a touch at any speed takes them so.
        assert_eq!(pvt3_session_new_touch(c, 50.0, 0.0, &mut s), PVT3_OK);
        for _ in 0..75 {
            assert_eq!(pvt3_session_push_frame(s, frames.as_ptr(), 60), PVT3_OK);
        }
        let mut class = 99usize;
        assert_eq!(pvt3_session_finish(s, probs.as_mut_ptr(), 20, &mut class), PVT3_OK);
        assert_eq!(class, best[0], "a constant window read as recorded = the same window batched");
        pvt3_session_free(s);
        assert_eq!(pvt3_session_new(c, &mut s), PVT3_OK);
        pvt3_classifier_free(c); // the session outlives its classifier
        assert_eq!(pvt3_session_push_frame(s, null(), 60), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_push_frame(s, frames.as_ptr(), 59), PVT3_ERR_INPUT);
        assert!(last_error().contains("a frame has 59 values; expected 60"), "{}", last_error());
        assert_eq!(pvt3_session_finish(s, probs.as_mut_ptr(), 40, null_mut()), PVT3_ERR_INPUT);
        assert!(last_error().contains("has 0 of its 75 frames"), "{}", last_error());
        let (mut used, mut stop) = (0usize, 7);
        assert_eq!(pvt3_session_peek(s, probs.as_mut_ptr(), 40, null_mut(), &mut used, &mut stop), PVT3_ERR_INPUT);
        assert!(last_error().contains("no whole temporal token"), "{}", last_error());
        for t in 0..75 {
            assert_eq!(pvt3_session_push_frame(s, frames.as_ptr(), 60), PVT3_OK);
            if t == 29 {
                assert_eq!(pvt3_session_peek(s, null_mut(), 40, null_mut(), null_mut(), null_mut()), PVT3_ERR_NULL);
                assert_eq!(pvt3_session_peek(s, probs.as_mut_ptr(), 19, null_mut(), null_mut(), null_mut()), PVT3_ERR_INPUT);
                let mut class = 99usize;
                assert_eq!(pvt3_session_peek(s, probs.as_mut_ptr(), 20, &mut class, &mut used, &mut stop), PVT3_OK);
                assert!(class < 20 && (probs[..20].iter().sum::<f32>() - 1.0).abs() < 1e-5);
                assert_eq!((used, stop), (30, 0), "30 frames read; the golden file has no stopping rule");
                assert_eq!(pvt3_session_peek(s, probs.as_mut_ptr(), 20, null_mut(), null_mut(), null_mut()), PVT3_OK);
            }
        }
        let mut peeked = 99usize;
        assert_eq!(pvt3_session_peek(s, probs.as_mut_ptr(), 20, &mut peeked, &mut used, null_mut()), PVT3_OK);
        assert_eq!((peeked, used), (best[0], 75), "with every frame in, a peek is the whole window's answer");
        assert_eq!(pvt3_session_push_frame(s, frames.as_ptr(), 60), PVT3_ERR_INPUT);
        assert_eq!(pvt3_session_finish(s, null_mut(), 40, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_finish(s, probs.as_mut_ptr(), 19, null_mut()), PVT3_ERR_INPUT);
        let mut class = 99usize;
        assert_eq!(pvt3_session_finish(s, probs.as_mut_ptr(), 20, &mut class), PVT3_OK);
        assert_eq!(class, best[0], "a constant window streamed = the same window batched");
        // A touch ended early (a robot stopping on a peek), reset: the next touch starts afresh.
        let other = vec![3.0f32; 60];
        for _ in 0..30 {
            assert_eq!(pvt3_session_push_frame(s, other.as_ptr(), 60), PVT3_OK);
        }
        assert_eq!(pvt3_session_reset(s), PVT3_OK);
        for _ in 0..75 {
            assert_eq!(pvt3_session_push_frame(s, frames.as_ptr(), 60), PVT3_OK);
        }
        let mut again = vec![0f32; 20];
        assert_eq!(pvt3_session_finish(s, again.as_mut_ptr(), 20, &mut class), PVT3_OK);
        assert_eq!((class, &again[..]), (best[0], &probs[..20]), "after a reset, the next touch alone");
        pvt3_session_free(s);

        let dir = scratch("files");
        let bytes = std::fs::read(golden("model.onnx")).unwrap();
        let mut flipped = bytes.clone();
        flipped[bytes.len() / 2] ^= 4;
        let damaged =
            [("truncated.onnx", bytes[..bytes.len() / 3].to_vec()), ("foreign.onnx", b"hello".to_vec()), ("flipped.onnx", flipped)];
        for (name, content) in damaged {
            let path = dir.join(name);
            std::fs::write(&path, content).unwrap();
            let p = CString::new(path.to_str().unwrap()).unwrap();
            assert_eq!(pvt3_classifier_load(p.as_ptr(), &mut c), PVT3_ERR_MODEL, "{name}: {}", last_error());
            assert!(last_error().contains(name) && last_error().contains("refused"), "{}", last_error());
        }
        // From memory: the same model; damaged bytes refused under the name given, or "(memory)".
        let name = CString::new("flash").unwrap();
        assert_eq!(pvt3_classifier_load_bytes(bytes.as_ptr(), bytes.len(), name.as_ptr(), &mut c), PVT3_OK);
        let window = vec![0.5f32; 4500];
        let mut from_memory = [0usize; 1];
        assert_eq!(pvt3_classify(c, window.as_ptr(), 4500, 1, probs.as_mut_ptr(), 20, from_memory.as_mut_ptr()), PVT3_OK);
        assert_eq!(from_memory[0], best[0], "a model from memory answers as the file does");
        // Threads: 0 refused; more than one where the library was built with the `threads` feature.
        assert_eq!(pvt3_classifier_set_threads(c, 0), PVT3_ERR_INPUT);
        let two = pvt3_classifier_set_threads(c, 2);
        assert_eq!(two, if cfg!(feature = "threads") { PVT3_OK } else { PVT3_ERR_INPUT }, "{}", last_error());
        assert_eq!(pvt3_classify(c, window.as_ptr(), 4500, 1, probs.as_mut_ptr(), 20, from_memory.as_mut_ptr()), PVT3_OK);
        assert_eq!(from_memory[0], best[0]);
        pvt3_classifier_free(c);
        let half = &bytes[..bytes.len() / 2];
        assert_eq!(pvt3_classifier_load_bytes(half.as_ptr(), half.len(), name.as_ptr(), &mut c), PVT3_ERR_MODEL);
        assert!(last_error().contains("flash"), "{}", last_error());
        assert_eq!(pvt3_classifier_load_bytes(half.as_ptr(), half.len(), null(), &mut c), PVT3_ERR_MODEL);
        assert!(last_error().contains("(memory)"), "{}", last_error());
        // A hostile file, damaged inside and signed again, sizes no machine can allocate: a status.
        let (hostile, initializer) = support::damaged_camera_file();
        assert_eq!(pvt3_classifier_load_bytes(hostile.as_ptr(), hostile.len(), name.as_ptr(), &mut c), PVT3_ERR_MODEL);
        assert!(last_error().contains(&format!("initializer `{initializer}` is of shape")), "{}", last_error());
        let absent = CString::new(dir.join("absent.onnx").to_str().unwrap()).unwrap();
        assert_eq!(pvt3_classifier_load(absent.as_ptr(), &mut c), PVT3_ERR_IO);
        std::fs::remove_dir_all(dir).unwrap();
    }
}

/// A camera's 8-bit frames through the C ABI: to a model without a camera reading (the golden
/// iCub file) the bytes are its frames, so a touch pushed as bytes answers as the same touch
/// pushed as floats; null pointers and wrong lengths are refused.
#[test]
fn camera_frames_go_in_as_bytes() {
    let model = CString::new(golden("model.onnx").to_str().unwrap()).unwrap();
    let bytes: Vec<Vec<u8>> = (0..75).map(|t| (0..60).map(|i| ((i * 7 + t * 3) % 256) as u8).collect()).collect();
    unsafe {
        let (mut c, mut s, mut n) = (null_mut(), null_mut(), 0usize);
        assert_eq!(pvt3_classifier_load(model.as_ptr(), &mut c), PVT3_OK);
        assert_eq!(pvt3_classifier_camera_frame_len(c, null_mut()), PVT3_ERR_NULL);
        assert_eq!(pvt3_classifier_camera_frame_len(c, &mut n), PVT3_OK);
        assert_eq!(n, 60);
        assert_eq!(pvt3_session_new(c, &mut s), PVT3_OK);
        let (mut as_bytes, mut as_floats) = (vec![0f32; 20], vec![0f32; 20]);
        for frame in &bytes {
            assert_eq!(pvt3_session_push_camera_frame(s, frame.as_ptr(), 60), PVT3_OK);
        }
        assert_eq!(pvt3_session_finish(s, as_bytes.as_mut_ptr(), 20, null_mut()), PVT3_OK);
        for frame in &bytes {
            let floats: Vec<f32> = frame.iter().map(|v| f32::from(*v)).collect();
            assert_eq!(pvt3_session_push_frame(s, floats.as_ptr(), 60), PVT3_OK);
        }
        assert_eq!(pvt3_session_finish(s, as_floats.as_mut_ptr(), 20, null_mut()), PVT3_OK);
        assert_eq!(as_bytes, as_floats);
        assert_eq!(pvt3_session_push_camera_frame(null_mut(), bytes[0].as_ptr(), 60), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_push_camera_frame(s, null(), 60), PVT3_ERR_NULL);
        assert_eq!(pvt3_session_push_camera_frame(s, bytes[0].as_ptr(), 59), PVT3_ERR_INPUT);
        assert!(last_error().contains("a frame has 59 values; expected 60"), "{}", last_error());
        pvt3_session_free(s);
        pvt3_classifier_free(c);
    }
}

/// A C string the library gave, as Rust text (None for NULL).
unsafe fn text(p: *const std::ffi::c_char, len: usize) -> Option<String> {
    (!p.is_null()).then(|| {
        let s = CStr::from_ptr(p).to_str().unwrap().to_string();
        assert_eq!(s.len(), len, "the length given is the string's");
        s
    })
}

/// What the C ABI says of a file, and answers, is what the Rust API says: the window's layout,
/// the kept frames, whether it streams, every metadata entry, the logits, a camera's touches
/// whole, and the sessions' counters; on the golden file and the shipped ones (a `pvt3 final`
/// iCub file, a BioTac file with a spectral head).
#[test]
fn c_sees_what_rust_sees() {
    let shipped = |name: &str| root().join("../shipped").join(name);
    for path in [golden("model.onnx"), shipped("icub20.onnx"), shipped("biotac20.onnx")] {
        let rust = Classifier::load(&path).unwrap();
        let model = CString::new(path.to_str().unwrap()).unwrap();
        unsafe {
            let mut c = null_mut();
            assert_eq!(pvt3_classifier_load(model.as_ptr(), &mut c), PVT3_OK);
            let (mut shape, mut rank) = ([0usize; 4], 0usize);
            assert_eq!(pvt3_classifier_input_shape(c, shape.as_mut_ptr(), 2, &mut rank), PVT3_ERR_INPUT);
            assert_eq!(rank, rust.sample_shape().len(), "the rank, also when the room is short");
            assert_eq!(pvt3_classifier_input_shape(c, shape.as_mut_ptr(), 4, &mut rank), PVT3_OK);
            assert_eq!(&shape[..rank], rust.sample_shape());
            let (mut h, mut w, mut ch) = (0usize, 0usize, 0usize);
            assert_eq!(pvt3_classifier_camera_shape(c, &mut h, &mut w, &mut ch), PVT3_OK);
            assert_eq!([h, w, ch], rust.camera_frame_shape());
            assert_eq!(h * w * ch, rust.camera_frame_len());
            let (mut kept, mut count) = (vec![0usize; 400], 0usize);
            assert_eq!(pvt3_classifier_kept_frames(c, kept.as_mut_ptr(), kept.len(), &mut count), PVT3_OK);
            assert_eq!(&kept[..count], rust.kept_frames());
            let mut streams = 7;
            assert_eq!(pvt3_classifier_streams(c, &mut streams), PVT3_OK);
            assert_eq!(streams, c_int::from(rust.streams()));

            // Every metadata entry, by index and by key.
            let mut entries = 0usize;
            assert_eq!(pvt3_classifier_metadata_count(c, &mut entries), PVT3_OK);
            assert_eq!(entries, rust.metadata().len());
            for (i, (key, value)) in rust.metadata().iter().enumerate() {
                let (mut p, mut len) = (null(), 0usize);
                assert_eq!(pvt3_classifier_metadata_key(c, i, &mut p, &mut len), PVT3_OK);
                assert_eq!(text(p, len).as_ref(), Some(key));
                let k = CString::new(key.as_str()).unwrap();
                assert_eq!(pvt3_classifier_metadata(c, k.as_ptr(), &mut p, &mut len), PVT3_OK);
                assert_eq!(text(p, len).as_ref(), Some(value));
            }
            let (mut p, mut len) = (null(), 5usize);
            assert_eq!(pvt3_classifier_metadata_key(c, entries, &mut p, &mut len), PVT3_ERR_INPUT);
            assert_eq!(pvt3_classifier_metadata(c, c"pvt3.absent".as_ptr(), &mut p, &mut len), PVT3_OK);
            assert_eq!((p, len), (null(), 0), "a key the file lacks: NULL, 0");
            let format = rust.metadata_value(pvt3_format::keys::FORMAT).expect("every file states its format");
            assert_eq!(format, format!("{}.{}", pvt3_format::FORMAT_VERSION.0, pvt3_format::FORMAT_VERSION.1));

            // Logits: Rust's, and their softmax is what pvt3_classify answers.
            let sample: usize = rust.sample_shape().iter().product();
            let classes = rust.classes().len();
            let x: Vec<f32> = (0..2 * sample).map(|i| ((i * 37) % 101) as f32 / 50.0 - 1.0).collect();
            let (mut logits, mut probs) = (vec![0f32; 2 * classes], vec![0f32; 2 * classes]);
            assert_eq!(pvt3_classify_logits(c, x.as_ptr(), x.len(), 2, logits.as_mut_ptr(), logits.len() - 1), PVT3_ERR_INPUT);
            assert_eq!(pvt3_classify_logits(c, x.as_ptr(), x.len(), 2, logits.as_mut_ptr(), logits.len()), PVT3_OK);
            let (rust_logits, rust_probs) = rust.run(&x, 2).unwrap();
            assert_eq!(logits, rust_logits);
            assert_eq!(pvt3_classify(c, x.as_ptr(), x.len(), 2, probs.as_mut_ptr(), probs.len(), null_mut()), PVT3_OK);
            assert_eq!(probs, rust_probs);

            // Camera touches whole, as Rust classifies them; and a session's counter.
            let frame_len = rust.camera_frame_len();
            let frames = rust.sample_shape().last().copied().unwrap();
            let bytes: Vec<u8> = (0..2 * frame_len * frames).map(|i| (i * 29 % 253) as u8).collect();
            let mut best = [9usize; 2];
            assert_eq!(
                pvt3_classify_camera_touches(c, bytes.as_ptr(), bytes.len(), 2, probs.as_mut_ptr(), probs.len(), best.as_mut_ptr()),
                PVT3_OK
            );
            let whole = rust.classify_camera_touches(&bytes, 2).unwrap();
            assert_eq!(best.to_vec(), whole.iter().map(|p| p.class).collect::<Vec<_>>());
            assert_eq!(probs, whole.iter().flat_map(|p| p.probabilities.clone()).collect::<Vec<_>>());
            assert_eq!(
                pvt3_classify_camera_touches(c, bytes.as_ptr(), bytes.len() - 1, 2, probs.as_mut_ptr(), probs.len(), null_mut()),
                PVT3_ERR_INPUT
            );
            let mut s = null_mut();
            assert_eq!(pvt3_session_new(c, &mut s), PVT3_OK);
            let frame = vec![0.25f32; frame_len];
            let mut received = 9usize;
            for t in 0..3 {
                assert_eq!(pvt3_session_received(s, &mut received), PVT3_OK);
                assert_eq!(received, t);
                assert_eq!(pvt3_session_push_frame(s, frame.as_ptr(), frame_len), PVT3_OK);
            }
            pvt3_session_free(s);
            let (mut k, mut answered, mut taken) = (null_mut(), 0, 9u64);
            assert_eq!(pvt3_continuous_new(c, 1, &mut k), PVT3_OK);
            for _ in 0..5 {
                assert_eq!(
                    pvt3_continuous_push_frame(k, frame.as_ptr(), frame_len, probs.as_mut_ptr(), classes, null_mut(), &mut answered),
                    PVT3_OK
                );
            }
            assert_eq!(pvt3_continuous_received(k, &mut taken), PVT3_OK);
            assert_eq!(taken, 5);
            assert_eq!(pvt3_continuous_reset(k), PVT3_OK);
            assert_eq!(pvt3_continuous_received(k, &mut taken), PVT3_OK);
            assert_eq!(taken, 0);
            pvt3_continuous_free(k);
            pvt3_classifier_free(c);
        }
    }
}
