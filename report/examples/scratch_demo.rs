use std::collections::BTreeMap;
use report::spec::*;
fn main() {
    let fixed: Vec<String> = ["accel","split","leaf_size","sah_bins","traversal","strategy","threads"].map(String::from).to_vec();
    let series = vec!["serial·list".to_string(), "serial·bvh".into(), "rayon·bvh".into()];
    let spec = ReportSpec {
        name: "demo".into(), description: "demo".into(), reference: Some("serial·bvh".into()), series: series.clone(),
        series_fixed: series.iter().map(|s| (s.clone(), fixed.clone())).collect::<BTreeMap<_,_>>(),
        plots: vec![
            PlotSpec { file: "time".into(), title: "Total time vs objects".into(), kind: PlotKind::Metric, x: "objects".into(), y: "total_s".into(), log_x: true, log_y: true, series: vec![] },
            PlotSpec { file: "speedup".into(), title: "Speedup vs objects".into(), kind: PlotKind::Speedup, x: "objects".into(), y: "total_s".into(), log_x: true, log_y: false, series: vec![] },
            PlotSpec { file: "eff".into(), title: "Efficiency vs threads".into(), kind: PlotKind::Efficiency, x: "threads".into(), y: "total_s".into(), log_x: false, log_y: false, series: vec!["rayon·bvh".into()] },
        ],
        claims: vec![ClaimSpec { text: "rayon is 0.5/thread".into(), paper: Some("x".into()), kind: ClaimKind::Faster { series: "rayon·bvh".into(), than: "serial·bvh".into(), factor: 0.5, per_thread: true }, metric: "total_s".into(), min_objects: None, max_objects: None }],
        config_text: "x = 1".into(), notes: vec![],
    };
    let t = std::time::Instant::now();
    let out = report::write(std::path::Path::new("/tmp/demo"), &spec).unwrap();
    eprintln!("{:?} in {:?}", out.claims, t.elapsed());
}
