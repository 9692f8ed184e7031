//! The fast subset: golden weights (identity normalisation) at the extremes of each kind of input.

use std::path::Path;

use pvt3_models::Config;
use pvt3_spec::bake::bake;
use pvt3_spec::normalization::Normalization;
use pvt3_spec::weights::read_tensors;

use super::*;
use crate::provenance::Provenance;

#[test]
fn the_runtime_stays_finite_and_close_to_the_f64_reference_on_extreme_inputs() {
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/golden/icub20/weights.safetensors");
    let cfg = Config::icub20();
    let file = BakedFile {
        baked: bake(&cfg, &read_tensors(&golden).unwrap()).unwrap(),
        normalization: Normalization { mean: vec![0.0; 60], std: vec![1.0; 60], frames: 75 },
        classes: (0..20).map(|k| format!("c{k}")).collect(),
        provenance: Provenance { data: "tests/golden/icub20".into(), ..Provenance::example() },
    };
    let scratch = std::env::temp_dir().join(format!("pvt3-stress-test-{}", std::process::id()));
    std::fs::create_dir_all(&scratch).unwrap();
    let rows = stress(&file, 2, true, &scratch).unwrap();
    std::fs::remove_dir_all(&scratch).unwrap();
    print!("{}", table(&rows));
    assert_eq!(rows.len(), 10);
    for r in &rows {
        assert_eq!(r.non_finite, 0, "{r:?}");
        assert!(r.worst_rel <= 1e-5, "{r:?}");
        assert_eq!(r.same_class, r.windows, "{r:?}");
    }
}
