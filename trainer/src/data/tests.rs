//! Loading the shipped sets and the errors a user's own files can provoke.

use std::path::{Path, PathBuf};

use ndarray::{ArrayD, IxDyn};
use ndarray_npy::{NpzWriter, WritableElement};

use super::*;

fn shipped(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../data").join(name)
}

fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-data-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_npz(path: &Path, fill: &dyn Fn(&mut NpzWriter<std::fs::File>)) {
    let mut w = NpzWriter::new(std::fs::File::create(path).unwrap());
    fill(&mut w);
    w.finish().unwrap();
}

fn array<T: WritableElement + Clone>(shape: &[usize], values: Vec<T>) -> ArrayD<T> {
    ArrayD::from_shape_vec(IxDyn(shape), values).unwrap()
}

#[test]
fn shipped_icub20_loads_with_its_folds() {
    let d = Dataset::load(&shipped("icub20.npz"), 0).unwrap();
    assert_eq!((d.len(), d.sample_shape.clone(), d.classes()), (1000, vec![6, 10, 75], 20));
    assert_eq!(d.fold_seed, None);
    let s = d.split(1).unwrap();
    assert_eq!((s.train.len(), s.val.len(), s.test.len()), (600, 200, 200));
    assert!(s.val.iter().all(|i| d.folds[*i] == 1) && s.test.iter().all(|i| d.folds[*i] == 4));
    d.check_fits(&pvt3_models::Config::icub20()).unwrap();
}

#[test]
fn shipped_biotac20_int16_reads_as_an_electrode_column() {
    let d = Dataset::load(&shipped("biotac20.npz"), 0).unwrap();
    assert_eq!(d.sample_shape, vec![19, 1, 400]);
    assert!((0..d.len()).all(|i| d.sample(i).iter().all(|v| (0.0..=3396.0).contains(v))));
    d.check_fits(&pvt3_models::Config::biotac20()).unwrap();
    let msg = d.check_fits(&pvt3_models::Config::icub20()).unwrap_err().to_string();
    assert!(msg.contains("samples are [19, 1, 400] but the model expects [6, 10, 75]"), "{msg}");
}

#[test]
fn a_set_without_folds_gets_balanced_stratified_folds() {
    let dir = temp_dir("nofold");
    let path = dir.join("set.npz");
    let labels: Vec<i64> = (0..50).map(|i| i % 2).collect();
    write_npz(&path, &|w| {
        w.add_array("x", &array(&[50, 3, 4], vec![1.0f64; 600])).unwrap();
        w.add_array("y", &array(&[50], labels.clone())).unwrap();
    });
    let d = Dataset::load(&path, 3).unwrap();
    assert_eq!(d.fold_seed, Some(3));
    for f in 0..FOLDS {
        let members: Vec<usize> = (0..50).filter(|&i| d.folds[i] == f).collect();
        assert_eq!(members.len(), 10);
        assert_eq!(members.iter().filter(|&&i| d.labels[i] == 0).count(), 5);
    }
    assert_eq!(d.folds, Dataset::load(&path, 3).unwrap().folds, "the seed fixes the folds");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_files_get_errors_that_say_what_was_expected() {
    let dir = temp_dir("bad");
    type Fill = Box<dyn Fn(&mut NpzWriter<std::fs::File>)>;
    let cases: Vec<(&str, Fill, &str)> = vec![
        (
            "nan",
            Box::new(|w| {
                let mut x = vec![0.0f32; 4 * 6];
                x[13] = f32::NAN;
                w.add_array("x", &array(&[4, 2, 3], x)).unwrap();
                w.add_array("y", &array(&[4], vec![0i64, 1, 0, 1])).unwrap();
            }),
            "NaN or infinite value in sample 2",
        ),
        (
            "label",
            Box::new(|w| {
                w.add_array("x", &array(&[2, 2, 3], vec![0.0f32; 12])).unwrap();
                w.add_array("y", &array(&[2], vec![0.0f32, 1.5])).unwrap();
            }),
            "`y`[1] = 1.5 is not a whole number",
        ),
        (
            "rank",
            Box::new(|w| {
                w.add_array("x", &array(&[2, 6], vec![0.0f32; 12])).unwrap();
                w.add_array("y", &array(&[2], vec![0i64, 1])).unwrap();
            }),
            "expected [N, H, W, T], [N, C, T] or [N, H, W, C, T]",
        ),
        (
            "count",
            Box::new(|w| {
                w.add_array("x", &array(&[2, 2, 3], vec![0.0f32; 12])).unwrap();
                w.add_array("y", &array(&[3], vec![0i64, 1, 1])).unwrap();
            }),
            "`y` has shape [3]; expected [2], one per sample",
        ),
        (
            "fold",
            Box::new(|w| {
                w.add_array("x", &array(&[2, 2, 3], vec![0.0f32; 12])).unwrap();
                w.add_array("y", &array(&[2], vec![0i64, 1])).unwrap();
                w.add_array("fold", &array(&[2], vec![0i64, 7])).unwrap();
            }),
            "fold 7 is outside 0..=4",
        ),
        ("missing", Box::new(|w| w.add_array("x", &array(&[2, 2, 3], vec![0.0f32; 12])).unwrap()), "no array `y` (found: x)"),
    ];
    for (name, fill, expected) in cases {
        let path = dir.join(format!("{name}.npz"));
        write_npz(&path, &*fill);
        let msg = Dataset::load(&path, 0).unwrap_err().to_string();
        assert!(msg.contains(expected), "{name}: {msg}");
        assert!(msg.contains(&path.display().to_string()), "{name}: the message names the file: {msg}");
    }
    let msg = Dataset::load(&dir.join("absent.npz"), 0).unwrap_err().to_string();
    assert!(msg.contains("no such file or directory"), "{msg}");
    std::fs::write(dir.join("text.npz"), "hello").unwrap();
    let msg = Dataset::load(&dir.join("text.npz"), 0).unwrap_err().to_string();
    assert!(msg.contains("not a readable .npz archive"), "{msg}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_directory_of_npy_files_loads_like_an_npz() {
    use ndarray_npy::write_npy;
    let dir = temp_dir("npydir");
    write_npy(dir.join("x.npy"), &array(&[5, 2, 2, 3], (0..60).map(|v| v as u8).collect())).unwrap();
    write_npy(dir.join("y.npy"), &array(&[5], vec![0i32, 1, 2, 0, 1])).unwrap();
    write_npy(dir.join("fold.npy"), &array(&[5], vec![0i64, 1, 2, 3, 4])).unwrap();
    let d = Dataset::load(&dir, 0).unwrap();
    assert_eq!((d.sample_shape.clone(), d.classes(), d.folds.clone()), (vec![2, 2, 3], 3, vec![0, 1, 2, 3, 4]));
    assert_eq!(d.sample(1)[0], 12.0);
    assert!(matches!(*d.x, crate::data::Frames::U8 { background: None, .. }), "8-bit frames stay 8-bit");
    // A single number for `x`, 8-bit or not, is an error naming the file, not a panic.
    for dtype in ["u8", "f32"] {
        match dtype {
            "u8" => write_npy(dir.join("x.npy"), &ndarray::arr0(7u8)).unwrap(),
            _ => write_npy(dir.join("x.npy"), &ndarray::arr0(7f32)).unwrap(),
        }
        let msg = Dataset::load(&dir, 0).unwrap_err().to_string();
        assert!(msg.contains("`x` has shape []") && msg.contains(&dir.display().to_string()), "{dtype}: {msg}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}
