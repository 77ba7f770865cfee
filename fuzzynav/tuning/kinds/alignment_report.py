"""``fuzzynav study report`` of an alignment study: ``trials.csv`` and ``report.md``."""
from __future__ import annotations

from pathlib import Path

from fuzzynav.fileio import staged, write_atomic

__all__ = ["write_alignment_report"]


def write_alignment_report(plan, study, out, evaluate: bool = True) -> Path:
    """Write the report of ``plan``'s ``study`` into directory ``out`` (staged: all or
    nothing); returns the path of ``report.md``.

    ``report.md`` names the best trial and its numbers; with ``evaluate`` it also gives
    the train and held-out objective of the tuned rules beside the paper's rules (what the
    rule file's provenance records), or of the tuned constants beside ``align-kf``.
    """
    from fuzzynav.tuning.optuna_study import n_finished

    acfg, best = plan.acfg, plan.chosen(study)
    lines = [f"# Alignment study `{plan.name}`", "",
             f"Sampler `{acfg.study.sampler}` (seed {acfg.study.seed}), "
             f"{n_finished(study)} finished trials; filter `{acfg.filter}`, "
             f"azimuth weight {acfg.azimuth_weight:g}; objective (minimised): "
             "align_time_s / duration_s + weight * final_azimuth_arcmin / threshold.", "",
             f"Best trial {best.number}: objective {best.value:.4f}", "",
             "| parameter | value |", "|---|---|"]
    lines += [f"| {k} | {v:.4g} |" for k, v in best.params.items()]
    if evaluate:
        _, summary = plan.summary_of(study)
        plain = "align-kf" if acfg.constants else "paper"
        lines += ["", f"| runs | {'align-kf' if acfg.constants else 'paper rules'} | tuned |",
                  "|---|---|---|"]
        for group in ("train", "test"):
            if summary[group]:
                lines.append(f"| {group} | {summary[group][plain]:.4f} | "
                             f"{summary[group]['tuned']:.4f} |")
    frame = study.trials_dataframe(attrs=("number", "value", "state", "params"))
    text = "\n".join(lines) + "\n"
    with staged(Path(out), "study report", last=("report.md",)) as tmp:
        write_atomic(tmp / "trials.csv", lambda t: frame.to_csv(t, index=False))
        write_atomic(tmp / "report.md", lambda t: Path(t).write_text(text))
    return Path(out) / "report.md"
