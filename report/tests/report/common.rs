//! What the report tests share.

use std::collections::BTreeMap;

use report::spec::ReportSpec;

/// A spec named `name` comparing `series` against `reference`, every series fixing all settings but `objects` and
/// `seed`.
pub fn spec(name: &str, reference: &str, series: &[&str]) -> ReportSpec {
    let fixed: Vec<String> = schema::row::setting_names()
        .into_iter()
        .filter(|c| !["objects", "seed"].contains(c))
        .map(String::from)
        .collect();
    ReportSpec {
        name: name.into(),
        reference: Some(reference.into()),
        series: series.iter().map(|s| s.to_string()).collect(),
        series_fixed: series.iter().map(|s| (s.to_string(), fixed.clone())).collect::<BTreeMap<_, _>>(),
        ..ReportSpec::default()
    }
}
