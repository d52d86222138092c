//! `--shard env`: the shard of this task, read from the environment of a Slurm job array or a Kubernetes
//! indexed Job.

use crate::cli::ShardArg;
use crate::error::Error;

/// Shard `(I, N)` (1-based) of `arg`, reading variables through `var`: `env` takes the 0-based
/// `SLURM_ARRAY_TASK_ID` and `SLURM_ARRAY_TASK_COUNT`; `env/N` takes `SLURM_ARRAY_TASK_ID`, else
/// `JOB_COMPLETION_INDEX`, with N shards.
pub fn resolve(arg: ShardArg, var: impl Fn(&str) -> Option<String>) -> Result<(usize, usize), Error> {
    let (name, count) = match arg {
        ShardArg::Fixed(i, n) => return Ok((i, n)),
        ShardArg::Env(None) => ("env", None),
        ShardArg::Env(Some(n)) => ("env/N", Some(n)),
    };
    let number = |key: &str| -> Result<Option<usize>, Error> {
        match var(key).map(|v| v.trim().to_string()).filter(|v| !v.is_empty()) {
            None => Ok(None),
            Some(v) => v.parse().map(Some).map_err(|_| {
                Error::Input(format!("--shard {name}: {key}={v:?} is not a number (allowed: integers >= 0)"))
            }),
        }
    };
    let (id, count) = match count {
        None => match (number("SLURM_ARRAY_TASK_ID")?, number("SLURM_ARRAY_TASK_COUNT")?) {
            (Some(id), Some(count)) => (id, count),
            _ => {
                return Err(Error::Input(
                    "--shard env: SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT are not set (not a Slurm array task; \
                     allowed: --shard env in a job array, env/N with SLURM_ARRAY_TASK_ID or JOB_COMPLETION_INDEX, I/N)"
                        .into(),
                ));
            }
        },
        Some(n) => match (number("SLURM_ARRAY_TASK_ID")?, number("JOB_COMPLETION_INDEX")?) {
            (Some(id), _) | (None, Some(id)) => (id, n),
            (None, None) => {
                return Err(Error::Input(format!(
                    "--shard env/{n}: neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set (allowed: --shard \
                     env/N in a Slurm array task or a Kubernetes indexed Job, I/N elsewhere)"
                )));
            }
        },
    };
    if id >= count {
        return Err(Error::Input(format!(
            "--shard {name}: task index {id} is out of range for {count} shards (allowed: 0..={})",
            count.saturating_sub(1)
        )));
    }
    Ok((id + 1, count))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn vars<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| pairs.iter().find(|(name, _)| *name == k).map(|(_, v)| v.to_string())
    }

    #[test]
    fn slurm_array_variables_give_a_one_based_shard() {
        let env = [("SLURM_ARRAY_TASK_ID", "0"), ("SLURM_ARRAY_TASK_COUNT", "3")];
        assert_eq!(resolve(ShardArg::Env(None), vars(&env)).unwrap(), (1, 3));
        let env = [("SLURM_ARRAY_TASK_ID", "2"), ("SLURM_ARRAY_TASK_COUNT", "3")];
        assert_eq!(resolve(ShardArg::Env(None), vars(&env)).unwrap(), (3, 3));
        // A resubmitted array (`--array=2`) has a count of 1: env/N keeps the shard count.
        let env = [("SLURM_ARRAY_TASK_ID", "2"), ("SLURM_ARRAY_TASK_COUNT", "1")];
        assert_eq!(resolve(ShardArg::Env(Some(3)), vars(&env)).unwrap(), (3, 3));
        assert_eq!(resolve(ShardArg::Fixed(2, 4), vars(&[])).unwrap(), (2, 4));
    }

    #[test]
    fn kubernetes_indexed_jobs_need_an_explicit_count() {
        let env = [("JOB_COMPLETION_INDEX", "1")];
        assert_eq!(resolve(ShardArg::Env(Some(4)), vars(&env)).unwrap(), (2, 4));
        let e = resolve(ShardArg::Env(None), vars(&env)).unwrap_err();
        assert!(
            e.to_string().starts_with("--shard env: SLURM_ARRAY_TASK_ID and SLURM_ARRAY_TASK_COUNT are not set"),
            "{e}"
        );
    }

    #[test]
    fn missing_bad_or_out_of_range_variables_are_input_errors() {
        for (arg, env, want) in [
            (ShardArg::Env(Some(2)), &[][..], "neither SLURM_ARRAY_TASK_ID nor JOB_COMPLETION_INDEX is set"),
            (ShardArg::Env(None), &[("SLURM_ARRAY_TASK_ID", "1")][..], "SLURM_ARRAY_TASK_COUNT are not set"),
            (
                ShardArg::Env(Some(2)),
                &[("JOB_COMPLETION_INDEX", "x")][..],
                "JOB_COMPLETION_INDEX=\"x\" is not a number",
            ),
            (ShardArg::Env(Some(2)), &[("JOB_COMPLETION_INDEX", "2")][..], "task index 2 is out of range for 2 shards"),
        ] {
            let e = resolve(arg, vars(env)).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains(want), "{e}");
            assert!(!e.to_string().contains('\n'), "one line: {e}");
        }
    }

    #[test]
    fn shard_arguments_parse() {
        use crate::cli::parse_shard;
        assert_eq!(parse_shard("env"), Ok(ShardArg::Env(None)));
        assert_eq!(parse_shard("env/4"), Ok(ShardArg::Env(Some(4))));
        assert_eq!(parse_shard("2/4"), Ok(ShardArg::Fixed(2, 4)));
        for bad in ["env/0", "envy", "0/2", "3/2", "env/x", ""] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }
}
