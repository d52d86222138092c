//! Every committed `runs.csv` reads into typed rows, and every row's configuration id is recomputed from
//! its typed settings: the declaration reproduces the ids the results were recorded with.

use std::path::{Path, PathBuf};

fn committed_runs() -> Vec<PathBuf> {
    let results = Path::new(env!("CARGO_MANIFEST_DIR")).join("../results");
    let mut found = Vec::new();
    let mut stack = vec![results];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap().flatten() {
            let path = entry.path();
            if path.is_dir() {
                stack.push(path);
            } else if path.file_name().is_some_and(|n| n == "runs.csv") {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

#[test]
fn committed_rows_parse_and_keep_their_configuration_ids() {
    let files = committed_runs();
    assert!(files.len() >= 6, "found {files:?}");
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        let rows = schema::row::read_rows(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(rows.len(), text.lines().count() - 1, "{}", path.display());
        for row in &rows {
            let id = schema::row::config_id(&row.series, &row.settings());
            assert_eq!(id, row.config_id, "{}: {} {:?}", path.display(), row.series, row.settings());
        }
    }
}

#[test]
fn rows_round_trip_through_csv() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../results/baselines/ci/runs.csv");
    let text = std::fs::read_to_string(path).unwrap();
    let rows = schema::row::read_rows(&text).unwrap();
    let mut written = format!("{}\n", schema::row::header());
    for row in &rows {
        written.push_str(&schema::row::csv_line(row).unwrap());
    }
    assert_eq!(schema::row::read_rows(&written).unwrap(), rows);
}

#[test]
fn packet_size_rows_read_as_packet_and_embree_packet() {
    use schema::{Accel, EmbreePacket, Packet, PeerKind};
    // Rows of `results/packets` as recorded at cff5dab (one per series), before `packet_size` became `packet` and
    // `embree_packet`; the result set has been recorded anew since.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/packet-size-rows.csv");
    let text = std::fs::read_to_string(path).unwrap();
    let old: Vec<String> = csv::Reader::from_reader(text.as_bytes())
        .deserialize::<std::collections::HashMap<String, String>>()
        .map(|r| r.unwrap()["packet_size"].clone())
        .collect();
    let rows = schema::row::read_rows(&text).unwrap();
    let (mut packets, mut widths) = (std::collections::BTreeSet::new(), std::collections::BTreeSet::new());
    for (row, old) in rows.iter().zip(&old) {
        let rays: u32 = old.parse().unwrap();
        match row.accel {
            a if a.is_wide() => {
                assert_eq!(row.packet, Packet::of_rays(rays), "{}", row.series);
                packets.insert(rays);
            }
            Accel::Peer(PeerKind::EmbreePackets) => {
                assert_eq!(row.embree_packet, EmbreePacket::new(rays), "{}", row.series);
                widths.insert(rays);
            }
            _ => assert_eq!((row.packet, row.embree_packet), (None, None), "{}", row.series),
        }
    }
    assert_eq!(packets.into_iter().collect::<Vec<_>>(), [1, 8, 16, 64], "every grouping is among the ids checked");
    assert_eq!(widths.into_iter().collect::<Vec<_>>(), [8, 16]);
}
