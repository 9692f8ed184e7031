//! The ready-made files in `shipped/`: each is the file its row of `shipped/README.md` names (its
//! SHA-256), reproduces the row's test accuracy on the shipped data set's test fold in the robot
//! runtime, touch for touch, and the touch the README's first command classifies is that test
//! fold's first. The camera's file, a final model of a data set too large to ship, states the
//! accuracy its row expects and answers its touch as the row says, whole and streamed.

use pvt3_trainer::data::{Dataset, TEST_FOLD};
use sha2::{Digest, Sha256};

#[path = "support/workspace.rs"]
mod workspace;

use workspace::workspace;

/// A row of shipped/README.md's table: the file, its touches answered right of those tested, its
/// SHA-256.
struct Row {
    file: String,
    accuracy: String,
    right: usize,
    tested: usize,
    sha256: String,
}

fn rows() -> Vec<Row> {
    let text = std::fs::read_to_string(workspace().join("shipped/README.md")).unwrap();
    let rows: Vec<Row> = text
        .lines()
        .filter(|l| l.starts_with("| `shipped/"))
        .map(|l| -> Vec<&str> { l.trim_matches('|').split('|').map(str::trim).collect() })
        .filter(|cells| cells.len() == 4)
        .map(|cells| {
            let (right, tested) = cells[2].split_once(" of ").expect("`N of M` touches");
            Row {
                file: cells[0].trim_matches('`').to_string(),
                accuracy: cells[1].to_string(),
                right: right.parse().unwrap(),
                tested: tested.parse().unwrap(),
                sha256: cells[3].to_string(),
            }
        })
        .collect();
    assert!(!rows.is_empty(), "shipped/README.md lists no file");
    rows
}

#[test]
fn each_shipped_file_is_the_one_listed_and_scores_its_test_accuracy_in_the_runtime() {
    for row in rows() {
        let path = workspace().join(&row.file);
        let bytes = std::fs::read(&path).unwrap();
        let digest: String = Sha256::digest(&bytes).iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(digest, row.sha256, "{}", row.file);
        let set = path.file_stem().unwrap().to_str().unwrap();
        let data = Dataset::load(&workspace().join(format!("data/{set}.npz")), 0).unwrap();
        let test: Vec<usize> = (0..data.len()).filter(|&i| data.folds[i] == TEST_FOLD).collect();
        let classifier = pvt3_runtime::Classifier::load(&path).unwrap();
        let frames: Vec<f32> = test.iter().flat_map(|&i| data.sample(i).to_vec()).collect();
        let answers = classifier.classify_batch(&frames, test.len()).unwrap();
        let right = answers.iter().zip(&test).filter(|(a, &i)| a.class == data.labels[i] as usize).count();
        assert_eq!((right, test.len()), (row.right, row.tested), "{}", row.file);
        assert_eq!(format!("{:.4}", right as f64 / test.len() as f64), row.accuracy, "{}", row.file);
        // The README's first command classifies this touch: the test fold's first.
        let touch: ndarray::ArrayD<f32> = ndarray_npy::read_npy(workspace().join(format!("shipped/{set}-touch.npy"))).unwrap();
        assert_eq!(touch.iter().copied().collect::<Vec<f32>>(), data.sample(test[0]).to_vec(), "{set}-touch.npy");
    }
}

/// The camera table's rows: the file, the accuracy its cross-validation expects, its touch's
/// class, the class the file answers, its SHA-256.
fn camera_rows() -> Vec<[String; 5]> {
    let text = std::fs::read_to_string(workspace().join("shipped/README.md")).unwrap();
    let rows: Vec<[String; 5]> = text
        .lines()
        .filter(|l| l.starts_with("| `shipped/"))
        .map(|l| l.trim_matches('|').split('|').map(|c| c.trim().trim_matches('`').to_string()).collect::<Vec<_>>())
        .filter_map(|cells| cells.try_into().ok())
        .collect();
    assert!(!rows.is_empty(), "shipped/README.md lists no camera file");
    rows
}

#[test]
fn the_camera_file_is_the_one_listed_expects_its_accuracy_and_answers_its_touch() {
    for [file, expected, _, answered, sha256] in camera_rows() {
        let path = workspace().join(&file);
        let digest: String = Sha256::digest(std::fs::read(&path).unwrap()).iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(digest, sha256, "{file}");
        let classifier = pvt3_runtime::Classifier::load(&path).unwrap();
        let provenance: serde_json::Value =
            serde_json::from_str(classifier.metadata_value(pvt3_format::keys::PROVENANCE).unwrap()).unwrap();
        let e = &provenance["expected"];
        let f = |v: &serde_json::Value| format!("{:.4}", v.as_f64().unwrap());
        let stated = format!(
            "{} ± {} [{}, {}]",
            f(&e["mean_test_accuracy"]),
            f(&e["std_test_accuracy"]),
            f(&e["ci95_test_accuracy"][0]),
            f(&e["ci95_test_accuracy"][1])
        );
        assert_eq!(stated, expected, "{file}: the accuracy its cross-validation expects");
        let touch_path = path.with_file_name(format!("{}-touch.npy", path.file_stem().unwrap().to_str().unwrap()));
        let touch: ndarray::ArrayD<u8> = ndarray_npy::read_npy(&touch_path).unwrap();
        let values: Vec<f32> = touch.iter().map(|&v| f32::from(v)).collect();
        let whole = classifier.classify(&values).unwrap();
        assert_eq!(whole.label, answered, "{file} on its touch");
        // Streamed frame by frame, as a robot's camera gives them, the same answer.
        let frames = *classifier.sample_shape().last().unwrap();
        let mut session = classifier.session().unwrap();
        for t in 0..frames {
            let frame: Vec<f32> = values.iter().skip(t).step_by(frames).copied().collect();
            session.push_frame(&frame).unwrap();
        }
        let streamed = session.finish().unwrap();
        assert_eq!(streamed.class, whole.class, "{file}: streamed");
        assert!(streamed.probabilities.iter().zip(&whole.probabilities).all(|(a, b)| (a - b).abs() < 1e-5));
    }
}
