//! What a bag directory's metadata may say that is refused by name; the messages themselves are
//! read against bags written by rosbags and mcap-ros2-support in tests/bags.rs.

use super::*;

fn bag(tag: &str, metadata: &str, files: &[&str]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pvt3-bag-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(metadata::FILE), metadata).unwrap();
    for f in files {
        std::fs::write(dir.join(f), b"").unwrap();
    }
    dir
}

fn metadata(storage: &str, files: &[&str], compression: (&str, &str)) -> String {
    let list: String = files.iter().map(|f| format!("\n  - {f}")).collect();
    format!(
        "rosbag2_bagfile_information:\n  version: 9\n  storage_identifier: {storage}\n  relative_file_paths:{list}\n  compression_format: '{}'\n  compression_mode: '{}'\n",
        compression.0, compression.1
    )
}

#[test]
fn a_bag_directory_names_its_files_and_their_storage() {
    let dir = bag("files", &metadata("sqlite3", &["a_0.db3", "a_1.db3"], ("", "")), &["a_0.db3", "a_1.db3"]);
    assert!(is_bag(&dir));
    assert_eq!(Bag::open(&dir).unwrap().files, vec![(dir.join("a_0.db3"), Storage::Sqlite), (dir.join("a_1.db3"), Storage::Sqlite)]);
    std::fs::remove_dir_all(&dir).unwrap();
    let refused = [
        (metadata("mcap", &["a.mcap", "b.mcap"], ("", "")), vec!["a.mcap"], "metadata.yaml names b.mcap, which is not there"),
        (metadata("mcap", &["a.mcap.zstd"], ("zstd", "FILE")), vec!["a.mcap.zstd"], "compressed by rosbag2 (zstd, each file)"),
        (metadata("hdf5", &["a.h5"], ("", "")), vec!["a.h5"], "storage `hdf5` of a.h5, neither mcap nor sqlite3"),
        (metadata("mcap", &[], ("", "")), vec![], "names no data file"),
        ("topics: []".to_string(), vec![], "metadata.yaml is not rosbag2's"),
    ];
    for (i, (text, present, why)) in refused.into_iter().enumerate() {
        let dir = bag(&format!("refused{i}"), &text, &present);
        let err = Bag::open(&dir).err().unwrap();
        assert!(err.contains(why), "{i}: {err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn damaged_storage_files_are_refused_by_name() {
    let dir = bag("damaged", &metadata("mcap", &["a.mcap"], ("", "")), &[]);
    std::fs::write(dir.join("a.mcap"), b"\x89MCAP0\r\nnot a record").unwrap();
    let err = Bag::open(&dir).unwrap().topics().unwrap_err();
    assert!(err.contains("a.mcap: not a readable MCAP file"), "{err}");
    std::fs::write(dir.join(metadata::FILE), metadata("sqlite3", &["a.db3"], ("", ""))).unwrap();
    std::fs::write(dir.join("a.db3"), b"SQLite format 3\0 and nothing else").unwrap();
    let err = Bag::open(&dir).unwrap().topics().unwrap_err();
    assert!(err.contains("a.db3: not a readable"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}
