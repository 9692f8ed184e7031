//! Importing a generated CSV tree, and the errors a user's own files can provoke.

use std::path::PathBuf;

use super::*;
use crate::data::import::folder::NamePattern;
use crate::data::{Dataset, HoldOut};

#[path = "../../../../../tests/support/csv_tree.rs"]
mod csv_tree;

fn tree(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-import-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    csv_tree::write(&dir, 3, 6, 40, 64);
    dir
}

#[test]
fn a_csv_tree_imports_with_its_lengths_names_and_channels() {
    let dir = tree("ok");
    let set = read_folder(&dir, &ImportOptions::default()).unwrap();
    assert_eq!(set.channels, ["e1", "e2", "e3", "e4"]);
    let left: Vec<_> = set.left_out.iter().map(|(n, why)| (n.as_str(), *why)).collect();
    assert_eq!(left, [("time", "a time stamp by its name"), ("pressure_set", "constant")]);
    assert_eq!((set.classes.len(), set.per_class()), (3, vec![6, 6, 6]));
    let (shortest, longest) = set.length_range();
    assert!(shortest >= 40 && longest <= 64 && shortest < longest, "{shortest}..{longest}");
    let out = dir.join("set.npz");
    set.write_npz(&out).unwrap();
    let data = Dataset::load(&out, 0).unwrap();
    assert_eq!(data.sample_shape, vec![4, 1, longest]);
    assert_eq!(data.class_names.as_deref().unwrap(), ["material_0", "material_1", "material_2"]);
    assert_eq!(data.sources.as_ref().unwrap()[0], "material_0/touch_00.csv");
    assert_eq!(*data.lengths.iter().min().unwrap(), shortest);
    assert!(!data.equal_lengths());
    // Touch 0's first frame, channel e2, as the file has it.
    let text = std::fs::read_to_string(dir.join("material_0/touch_00.csv")).unwrap();
    let e2: f32 = text.lines().nth(1).unwrap().split(',').nth(2).unwrap().parse().unwrap();
    assert_eq!(data.sample(0)[longest], e2);
    // Chosen by pattern, laid out on a grid.
    let opts = ImportOptions { columns: vec!["e?".into()], grid: Some((2, 2)), ..Default::default() };
    let set = read_folder(&dir, &opts).unwrap();
    set.write_npz(&out).unwrap();
    assert_eq!(Dataset::load(&out, 0).unwrap().sample_shape, vec![2, 2, longest]);
    let err =
        read_folder(&dir, &ImportOptions { columns: vec!["e?".into()], grid: Some((3, 2)), ..Default::default() }).unwrap_err().to_string();
    assert!(err.contains("--grid 3x2 holds 6 channels, and 4 columns were chosen"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A 32 × 32 taxel grid from CSV is recorded as a tactile array's, whatever its size, and trains
/// as one: with the image's layout a taxel grid this large takes, said as an array's; `--sensor
/// camera` records it as a camera's instead.
#[test]
fn a_large_taxel_grid_is_recorded_as_an_array_and_trains_as_one() {
    let dir = std::env::temp_dir().join(format!("pvt3-import-grid-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let header = (0..1024).map(|i| format!("p{i}")).collect::<Vec<_>>().join(",");
    // Five touches a class, as the folds need.
    for (class, touch) in ["felt", "cork"].into_iter().flat_map(|c| (0..5).map(move |t| (c, t))) {
        std::fs::create_dir_all(dir.join(class)).unwrap();
        let rows: Vec<String> =
            (0..8).map(|t| (0..1024).map(|i| ((i * 7 + t * 13 + touch) % 97).to_string()).collect::<Vec<_>>().join(",")).collect();
        std::fs::write(dir.join(class).join(format!("t{touch}.csv")), format!("{header}\n{}\n", rows.join("\n"))).unwrap();
    }
    let out = dir.join("set.npz");
    for (asked, kind) in [(None, pvt3_spec::Sensor::Array), (Some(pvt3_spec::Sensor::Camera), pvt3_spec::Sensor::Camera)] {
        let columns = vec!["p*".to_string()];
        let set = read_folder(&dir, &ImportOptions { columns, grid: Some((32, 32)), sensor: asked, ..Default::default() }).unwrap();
        set.write_npz(&out).unwrap();
        let data = Dataset::load(&out, 0).unwrap();
        assert_eq!((data.sample_shape.clone(), data.sensor, data.sensor_recorded), (vec![32, 32, 8], kind, true));
        let configured = crate::configure::configure(&data, &Default::default(), &Default::default()).unwrap();
        let layout = configured.notes.iter().find(|n| n.starts_with("no preset takes samples of 32 × 32 × 8")).unwrap();
        let expected = match kind {
            pvt3_spec::Sensor::Array => "derived an image's layout for a taxel grid this large",
            pvt3_spec::Sensor::Camera => "derived a camera's layout,",
        };
        assert!(layout.contains(expected) && !layout.contains("does not record"), "{layout}");
    }
    // A long list of columns is elided where it is said.
    let wrong = ImportOptions { columns: vec!["p*".into()], grid: Some((31, 32)), ..Default::default() };
    let err = read_folder(&dir, &wrong).unwrap_err().to_string();
    assert!(err.contains("p9, p10, …, p1023 (1024 names)") && !err.contains("p500"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_files_are_named_with_their_line() {
    let dir = tree("bad");
    let touch = dir.join("material_1/touch_03.csv");
    let good = std::fs::read_to_string(&touch).unwrap();
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    let err = |dir: &Path, opts: &ImportOptions| read_folder(dir, opts).unwrap_err().to_string();

    lines[5].push_str(",9.9");
    std::fs::write(&touch, lines.join("\n")).unwrap();
    let msg = err(&dir, &ImportOptions::default());
    assert!(msg.contains("touch_03.csv:6: a ragged row: 7 fields, the header has 6"), "{msg}");

    lines[5] = good.lines().nth(5).unwrap().replacen(",1", ",oops", 1);
    std::fs::write(&touch, lines.join("\n")).unwrap();
    let msg = err(&dir, &ImportOptions { columns: vec!["e*".into()], ..Default::default() });
    assert!(msg.contains("touch_03.csv:6: column `e1` holds text, not a number"), "{msg}");
    // By default a column with text is left out, said so.
    let set = read_folder(&dir, &ImportOptions::default()).unwrap();
    assert!(set.left_out.contains(&("e1".into(), "not numeric")), "{:?}", set.left_out);
    std::fs::write(&touch, &good).unwrap();

    let msg = err(&dir, &ImportOptions { columns: vec!["force".into()], ..Default::default() });
    assert!(msg.contains("--columns force: no column of the header matches"), "{msg}");

    std::fs::create_dir_all(dir.join("material_9")).unwrap();
    let msg = err(&dir, &ImportOptions::default());
    assert!(msg.contains("material_9: an empty class"), "{msg}");
    for n in 0..3 {
        std::fs::write(dir.join(format!("material_9/t{n}.csv")), &good).unwrap();
    }
    let msg = err(&dir, &ImportOptions::default());
    assert!(msg.contains("material_9: 3 touches, too few to split"), "{msg}");
    std::fs::remove_dir_all(dir.join("material_9")).unwrap();

    std::fs::write(&touch, good.replacen("e4", "e5", 1)).unwrap();
    let msg = err(&dir, &ImportOptions::default());
    assert!(msg.contains("touch_03.csv:1: its header differs from"), "{msg}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn with_no_column_to_take_each_is_named_with_why() {
    let dir = std::env::temp_dir().join(format!("pvt3-import-nothing-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for class in ["cotton", "denim"] {
        std::fs::create_dir_all(dir.join(class)).unwrap();
        for n in 0..6 {
            std::fs::write(dir.join(format!("{class}/t{n}.csv")), "counter,level,note\n0,1,a\n1,1,b\n2,1,c\n").unwrap();
        }
    }
    let msg = read_folder(&dir, &ImportOptions::default()).unwrap_err().to_string();
    let want = "no column is a numeric channel that varies: `counter` a time stamp: it rises in every touch, `level` constant, `note` not numeric (";
    assert!(msg.starts_with(want) && msg.contains("t0.csv:2)"), "{msg}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn patterns_match_whole_names() {
    assert!(matches("ff_e*", "ff_e12") && matches("e?", "e1") && matches("*", ""));
    assert!(!matches("e?", "e12") && !matches("ff_e*", "ff_pdc") && !matches("e1", "e12"));
    assert!(matches("*a*b", "xaybzb") && matches("a*?c", "abbc") && !matches("a*?c", "ac") && matches("**", "x"));
}

/// A pattern that made backtracking try every split (exponential in its stars or fields) against
/// a long name answers at once.
#[test]
fn patterns_take_no_exponential_time() {
    let long = "a".repeat(5_000);
    let started = std::time::Instant::now();
    assert!(!matches("*a*a*a*a*a*a*a*b", &long));
    let p: NamePattern = "{a}_{b}_{c}_{d}_{e}_z".parse().unwrap();
    assert_eq!(p.read(&"_".repeat(3_000)), None);
    let fields = "x_".repeat(10) + "z";
    assert_eq!(p.read(&fields).unwrap(), ["x_x_x_x_x_x", "x", "x", "x", "x"]);
    assert!(started.elapsed().as_secs() < 10, "{:?}", started.elapsed());
}

#[test]
fn name_patterns_read_fields_and_refuse_what_cannot_be_told_apart() {
    let p: NamePattern = "{class}_F{force}_V{speed}mmps_*".parse().unwrap();
    assert_eq!(p.fields(), ["class", "force", "speed"]);
    assert_eq!(p.conditions(), ["force", "speed"]);
    assert_eq!(p.read("DenimFlex_F210_V-150mmps_3").unwrap(), ["DenimFlex", "210", "-150"]);
    assert_eq!(p.read("Linen_F120_V10mmps_0").unwrap(), ["Linen", "120", "10"]);
    assert_eq!(p.read("Linen_F120_V10mm_0"), None);
    assert_eq!(p.read("_F120_V10mmps_0"), None, "a field reads at least one character");
    // Fields take the longest run that lets the rest match: an object's name holds underscores.
    let p: NamePattern = "{a}_{b}".parse().unwrap();
    assert_eq!(p.read("x_y_z").unwrap(), ["x_y", "z"]);
    let p: NamePattern = "{class}_*".parse().unwrap();
    assert_eq!(p.read("aluminium_foil_3").unwrap(), ["aluminium_foil"]);
    for (bad, why) in [
        ("{a}{b}", "side by side"),
        ("{a}*", "side by side"),
        ("{a", "not a field"),
        ("{}", "not a field"),
        ("a}", "without its"),
        ("{a}_{a}", "twice"),
    ] {
        let err = bad.parse::<NamePattern>().unwrap_err();
        assert!(err.contains(why), "{bad}: {err}");
    }
}

/// Touches side by side in one folder, their class and conditions in their names, as FabricSlide
/// names them.
fn flat_tree(tag: &str) -> PathBuf {
    let dir = tree(tag);
    csv_tree::flatten(&dir, &dir.join("flat"), 3, 6);
    dir.join("flat")
}

#[test]
fn a_flat_folder_imports_classes_and_conditions_from_names() {
    let flat = flat_tree("flat");
    let naming = Naming::Pattern("{class}_F{force}_V{speed}mmps_*".parse().unwrap());
    let set = read_folder(&flat, &ImportOptions { naming, ..Default::default() }).unwrap();
    assert_eq!(set.classes, ["Fabric0", "Fabric1", "Fabric2"]);
    assert_eq!(set.per_class(), [6, 6, 6]);
    let names: Vec<&str> = set.conditions.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["force", "speed"]);
    let out = flat.join("set.npz");
    set.write_npz(&out).unwrap();
    let mut data = Dataset::load(&out, 0).unwrap();
    assert_eq!(data.conditions, set.conditions);
    let levels = |l: &[&str]| crate::data::Condition { name: "speed".into(), levels: l.iter().map(|v| v.to_string()).collect() };
    assert_eq!(levels(&["100", "20", "-150", "20"]).distinct(), ["-150", "20", "100"], "numbers in numeric order");
    assert_eq!(levels(&["b", "a10", "a2"]).distinct(), ["a10", "a2", "b"], "text in text order");
    let at = data.sources.as_ref().unwrap().iter().position(|s| s == "Fabric1_F210_V50mmps_5.csv").unwrap();
    assert_eq!((data.labels[at], data.conditions[0].levels[at].as_str(), data.conditions[1].levels[at].as_str()), (1, "210", "50"));

    // Holding out a level: its touches and no other test; the rest fill the other folds.
    let hold = |condition: &str, level: &str, seed| HoldOut { condition: condition.into(), levels: vec![level.into()], seed, class: None };
    data.hold_out(&hold("force", "210", 3)).unwrap();
    for i in 0..data.len() {
        assert_eq!(data.folds[i] == crate::data::TEST_FOLD, data.conditions[0].levels[i] == "210", "touch {i}");
    }
    assert_eq!(data.held_out.as_ref().unwrap().to_string(), "force=210");
    let again = Dataset::load_as_trained(&out, 0, data.held_out.as_ref(), None).unwrap();
    assert_eq!(again.folds, data.folds, "a run that recorded no split has its folds drawn again as it was trained");
    let recorded = Dataset::load_as_trained(&out, 5, None, Some(&data.trained_on(false))).unwrap();
    assert_eq!((&recorded.folds, recorded.fold_seed), (&data.folds, Some(3)), "a recorded split is taken as it is");
    let split = data.split(0).unwrap();
    assert_eq!((split.test.len(), split.val.len() + split.train.len()), (6, 12));
    let msg = |name: &str, level: &str| data.clone().hold_out(&hold(name, level, 0)).unwrap_err().to_string();
    assert!(
        msg("force", "999").contains("--hold-out force=999: no touch has that level; force has 120, 150, 210"),
        "{}",
        msg("force", "999")
    );
    assert!(msg("pressure", "1").contains("no such condition; the set records force, speed"));
    assert!(msg("speed", "-10").contains("keeps 3 touches, too few"), "{}", msg("speed", "-10"));

    // One class's touches of a level: they test, and every other class trains at that level too.
    let one = HoldOut { class: Some("Fabric1".into()), ..hold("force", "210", 3) };
    data.hold_out(&one).unwrap();
    for i in 0..data.len() {
        let held = data.labels[i] == 1 && data.conditions[0].levels[i] == "210";
        assert_eq!(data.folds[i] == crate::data::TEST_FOLD, held, "touch {i}");
    }
    assert!(data.folds.iter().zip(&data.conditions[0].levels).any(|(f, l)| *f != crate::data::TEST_FOLD && l == "210"));
    assert_eq!(data.held_out.as_ref().unwrap().to_string(), "force=210 of class Fabric1");
    assert!(one.same_touches(&HoldOut { seed: 0, ..one.clone() }) && !one.same_touches(&hold("force", "210", 3)));
    let again = Dataset::load_as_trained(&out, 0, Some(&one), None).unwrap();
    assert_eq!(again.folds, data.folds, "the class's hold-out is drawn again as it was trained");
    let silk = data.clone().hold_out(&HoldOut { class: Some("Silk".into()), ..one.clone() }).unwrap_err().to_string();
    assert!(silk.contains("no class is named Silk; the set's classes are Fabric0, Fabric1, Fabric2"), "{silk}");

    // Read by distance: a touch at -10 mm/s resampled to speed 50 keeps a fifth of its frames.
    let naming = Naming::Pattern("{class}_F{force}_V{speed}mmps_*".parse().unwrap());
    let by_distance =
        read_folder(&flat, &ImportOptions { naming, per_distance: Some(("speed".into(), 50.0)), ..Default::default() }).unwrap();
    for (k, touch) in by_distance.touches.iter().enumerate() {
        let slow = set.conditions[1].levels[k] == "-10";
        let expected = if slow { (set.touches[k][0].len() as f64 / 5.0).round() as usize } else { set.touches[k][0].len() };
        assert_eq!(touch[0].len(), expected, "touch {k}");
    }
    // Scaled to one force: a touch pressed at 210 reads 150/210 of its values.
    let naming = Naming::Pattern("{class}_F{force}_V{speed}mmps_*".parse().unwrap());
    let per_force = read_folder(&flat, &ImportOptions { naming, per_force: Some(("force".into(), 150.0)), ..Default::default() }).unwrap();
    for (k, touch) in per_force.touches.iter().enumerate() {
        let f: f32 = set.conditions[0].levels[k].parse().unwrap();
        let expected = set.touches[k][2][7] * (150.0 / f);
        assert!((touch[2][7] - expected).abs() <= 1e-5 * expected.abs(), "touch {k}: {} against {expected}", touch[2][7]);
    }
    let naming = Naming::Pattern("{class}_F{force}_V{speed}mmps_*".parse().unwrap());
    let err = read_folder(&flat, &ImportOptions { naming, per_distance: Some(("pace".into(), 50.0)), ..Default::default() }).unwrap_err();
    assert!(err.to_string().contains("--per-distance pace: no such condition"), "{err}");

    // A name the pattern does not fit is named.
    std::fs::write(flat.join("stray.csv"), "time,e1\n1,2\n").unwrap();
    let naming = Naming::Pattern("{class}_F{force}_V{speed}mmps_*".parse().unwrap());
    let err = read_folder(&flat, &ImportOptions { naming, ..Default::default() }).unwrap_err().to_string();
    assert!(err.contains("stray.csv: its name `stray` does not match --name {class}_F{force}_V{speed}mmps_*"), "{err}");
    std::fs::remove_dir_all(flat.parent().unwrap()).unwrap();
}

/// A labels file names each touch's class and conditions, whatever folders the touches lie in;
/// a listed file that is no touch is refused naming the labels file's line.
#[test]
fn a_labels_file_names_each_touch_s_class_and_conditions() {
    let dir = tree("labels");
    let mut text = String::from("path,grip,class\n");
    for k in 0..3 {
        for n in 0..6 {
            let class = if k == 2 { "smooth" } else { "rough" };
            text.push_str(&format!("material_{k}/touch_{n:02}.csv,{},{class}\n", n % 2));
        }
    }
    let file = dir.join("labels.csv");
    std::fs::write(&file, &text).unwrap();
    let naming = Naming::Labels(crate::data::import::labels::Labels::read(&file).unwrap());
    let set = read_folder(&dir, &ImportOptions { naming, ..Default::default() }).unwrap();
    assert_eq!((set.classes.as_slice(), set.per_class()), (&["rough".to_string(), "smooth".to_string()][..], vec![12, 6]));
    assert_eq!(set.sources[6], "material_1/touch_00.csv");
    assert_eq!(
        (set.conditions[0].name.as_str(), set.conditions[0].levels[..3].to_vec()),
        ("grip", vec!["0".to_string(), "1".into(), "0".into()])
    );
    std::fs::write(&file, text.replace("material_2/touch_05.csv", "material_2/gone.csv")).unwrap();
    let naming = Naming::Labels(crate::data::import::labels::Labels::read(&file).unwrap());
    let msg = read_folder(&dir, &ImportOptions { naming, ..Default::default() }).unwrap_err().to_string();
    assert!(msg.contains("labels.csv:19: material_2/gone.csv is not a .csv file"), "{msg}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// A reading beyond a 32-bit float's range is refused naming its file, line and column, where it
/// was stored as ±inf without a word; a name with a line break is refused naming its folder.
#[test]
fn readings_and_names_a_set_cannot_hold_are_refused_by_name() {
    let dir = tree("range");
    let touch = dir.join("material_1/touch_02.csv");
    let text = std::fs::read_to_string(&touch).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let mut cells: Vec<String> = lines[3].split(',').map(String::from).collect();
    cells[2] = "-1e39".into();
    lines[3] = cells.join(",");
    std::fs::write(&touch, lines.join("\n") + "\n").unwrap();
    let msg = read_folder(&dir, &ImportOptions::default()).unwrap_err().to_string();
    assert!(msg.contains("touch_02.csv:4: column `e2` holds -1e39, beyond the range of the 32-bit floats"), "{msg}");
    std::fs::write(&touch, text).unwrap();
    std::fs::rename(dir.join("material_2"), dir.join("material\n2")).unwrap();
    let msg = read_folder(&dir, &ImportOptions::default()).unwrap_err().to_string();
    assert!(msg.contains("holds a line break, and a data set keeps its names one a line"), "{msg}");
    std::fs::remove_dir_all(dir).unwrap();
}
