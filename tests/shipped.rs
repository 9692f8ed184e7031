//! The ready-made files in `shipped/`: each is the file its row of `shipped/README.md` names (its
//! SHA-256), reproduces the row's test accuracy on the shipped data set's test fold in the robot
//! runtime, touch for touch, and the touch the README's first command classifies is that test
//! fold's first.

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
        .map(|l| {
            let cells: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
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
