//! A folder of CSV touches as a user's sensor records them, for the import tests: one folder per
//! class, one file per touch of its own length, a header, a rising time stamp, a constant column
//! and four channels whose level and vibration frequency are the class's.

use std::fmt::Write;
use std::path::Path;

/// Writes `classes` × `touches` CSV files under `dir`, `min_len..=max_len` rows each.
pub fn write(dir: &Path, classes: usize, touches: usize, min_len: usize, max_len: usize) {
    let mut state = 7u64;
    let mut uniform = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for k in 0..classes {
        let class_dir = dir.join(format!("material_{k}"));
        std::fs::create_dir_all(&class_dir).unwrap();
        for n in 0..touches {
            let len = min_len + (uniform() * (max_len - min_len + 1) as f64) as usize;
            let mut text = String::from("time,e1,e2,e3,e4,pressure_set\n");
            let phase = uniform() * std::f64::consts::TAU;
            for t in 0..len {
                let _ = write!(text, "{:.3}", 1000.0 + t as f64 * 0.01);
                for e in 0..4 {
                    let wave = (0.15 * (k + 1) as f64 * t as f64 + phase + e as f64).sin();
                    let _ = write!(text, ",{:.3}", 100.0 + 10.0 * e as f64 + 4.0 * k as f64 + 5.0 * wave + uniform());
                }
                text.push_str(",2.5\n");
            }
            std::fs::write(class_dir.join(format!("touch_{n:02}.csv")), text).unwrap();
        }
    }
}

/// The touches of a tree `write` made (`touches` a class, at least 6), side by side in `flat` and
/// named as FabricSlide names its files, `Fabric{k}_F{force}_V{speed}mmps_{n}.csv`: the forces 120,
/// 150 and 210 in turn, the first half of each class's touches at -10 mm/s, the rest at 50.
pub fn flatten(dir: &Path, flat: &Path, classes: usize, touches: usize) {
    std::fs::create_dir_all(flat).unwrap();
    for k in 0..classes {
        for n in 0..touches {
            let (force, speed) = ([120, 150, 210][n % 3], if n < touches / 2 { -10 } else { 50 });
            let from = dir.join(format!("material_{k}/touch_{n:02}.csv"));
            std::fs::copy(from, flat.join(format!("Fabric{k}_F{force}_V{speed}mmps_{n}.csv"))).unwrap();
        }
    }
}
