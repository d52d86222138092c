//! Which settings a series makes irrelevant: those that apply to none of the configurations it can have.

use std::collections::BTreeMap;

use crate::columns::{APPLICABILITY_INPUTS, Axis, AxisValue, Settings};

/// The axes `fixed` names, plus every axis that applies to no configuration with those values (whatever
/// the other named axes take), plus those it forces to one value (threads of a serial series). Speedup
/// matching ignores them, so a series is compared with the reference whatever those columns say.
pub fn fixed_axes(fixed: &BTreeMap<Axis, Vec<AxisValue>>) -> Vec<Axis> {
    let free: Vec<Vec<AxisValue>> = Axis::ALL
        .iter()
        .map(|&a| match fixed.get(&a) {
            Some(values) => values.clone(),
            // Only the axes the predicates read change what applies: the others keep their default.
            None if APPLICABILITY_INPUTS.contains(&a) => a.choices().unwrap_or_else(|| vec![a.default_value()]),
            None => vec![a.default_value()],
        })
        .collect();
    let mut out: Vec<Axis> = fixed.keys().copied().collect();
    for &axis in Axis::ALL.iter().filter(|a| !fixed.contains_key(a) && !a.always_applies()) {
        let mut values = std::collections::BTreeSet::new();
        let mut applies_somewhere = false;
        each_combination(&free, |s| {
            let n = s.normalized();
            applies_somewhere |= n.applies(axis);
            values.insert(n.get(axis).to_string());
            !applies_somewhere
        });
        if !applies_somewhere && values.len() <= 1 {
            out.push(axis);
        }
    }
    out.sort();
    out
}

/// Calls `f` with every combination of `lists` (one list per axis, in [`Axis::ALL`] order) until it returns false.
fn each_combination(lists: &[Vec<AxisValue>], mut f: impl FnMut(&Settings) -> bool) {
    let mut index = vec![0usize; lists.len()];
    let mut settings = Settings::default();
    for list in lists {
        settings.set(list[0].clone());
    }
    loop {
        if !f(&settings) {
            return;
        }
        let mut i = lists.len();
        loop {
            if i == 0 {
                return;
            }
            i -= 1;
            index[i] += 1;
            if index[i] < lists[i].len() {
                settings.set(lists[i][index[i]].clone());
                break;
            }
            index[i] = 0;
            settings.set(lists[i][0].clone());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::names::Accel;
    use tracer::accel::AccelKind;
    use tracer::executor::StrategyKind;

    #[test]
    fn settings_that_apply_somewhere_are_not_fixed() {
        let flat = AxisValue::accel(Accel::Ours(AccelKind::FlatBvh));
        let fixed = fixed_axes(&BTreeMap::from([(Axis::accel, vec![flat])]));
        for axis in [Axis::split, Axis::leaf_size, Axis::traversal, Axis::threads, Axis::objects] {
            assert!(!fixed.contains(&axis), "{axis:?} applies to some flat-BVH configuration");
        }
        let serial = AxisValue::strategy(StrategyKind::Serial);
        assert!(fixed_axes(&BTreeMap::from([(Axis::strategy, vec![serial])])).contains(&Axis::threads));
        let wide = AxisValue::accel(Accel::Ours(AccelKind::WideBvh));
        let fixed = fixed_axes(&BTreeMap::from([(Axis::accel, vec![wide])]));
        assert!(
            fixed.contains(&Axis::traversal) && !fixed.contains(&Axis::node_width) && !fixed.contains(&Axis::split)
        );
        let flat = AxisValue::accel(Accel::Ours(AccelKind::FlatBvh));
        assert!(fixed_axes(&BTreeMap::from([(Axis::accel, vec![flat])])).contains(&Axis::simd_kernel));
    }

    #[test]
    fn only_the_declared_inputs_change_what_applies() {
        let lists: Vec<Vec<AxisValue>> = Axis::ALL
            .iter()
            .map(|&a| match a.choices() {
                Some(all) if APPLICABILITY_INPUTS.contains(&a) => all,
                _ => vec![a.default_value()],
            })
            .collect();
        let others: Vec<Axis> = Axis::ALL.iter().copied().filter(|a| !APPLICABILITY_INPUTS.contains(a)).collect();
        each_combination(&lists, |base| {
            let applies = |s: &Settings| Axis::ALL.iter().map(|&a| s.applies(a)).collect::<Vec<_>>();
            let want = applies(base);
            for &axis in &others {
                for value in axis.choices().unwrap_or_default() {
                    let mut s = base.clone();
                    s.set(value.clone());
                    assert_eq!(
                        applies(&s),
                        want,
                        "{axis:?} = {value} changes what applies: add it to APPLICABILITY_INPUTS"
                    );
                }
            }
            true
        });
    }
}
