"""``report.md`` of ``omnikin umbmark``: the ``result.json`` document in words and tables."""

from __future__ import annotations

from ..common.number_text import RESOLUTION, mm_text, ratio_text, reduction_bounded, reduction_text


def _interval_mm(interval) -> str:
    if not interval:
        return "n/a (needs 3 runs per direction)"
    return f"{mm_text(interval[0])} to {mm_text(interval[1])}"


def floor_limit(doc: dict) -> float:
    """The E_max,syst [m] at or below which a result of ``result.json`` ``doc`` is at its floor
    (``at_noise_floor``): the physics floor's ``e_max_syst_limit``, the noise floor's 95th percentile."""
    floor = doc["noise_floor"]
    return float(floor.get("e_max_syst_limit", floor["e_max_syst_p95"]))


def physics_floor_text(floor: dict, level: str) -> str:
    """The physics floor of ``result.json`` (``noise_floor``) in one sentence: median and 95th
    percentile over the procedures, and the confidence interval of the first one from its runs'
    spread over roller phases."""
    n = floor["procedures"]
    text = (
        f"E_max,syst {mm_text(floor['e_max_syst_median'])} mm"
        + (f" (median of {n} procedures, 95th percentile {mm_text(floor['e_max_syst_p95'])} mm)" if n > 1 else "")
        + ", every run at its own roller phases"
    )
    interval = floor.get("e_max_syst_interval")
    if interval:
        text += f"; {level} interval over the runs' spread {_interval_mm(interval)} mm"
    else:
        text += "; no interval (needs 3 runs per direction)"
    return text


def umbmark_markdown(report, doc: dict, figures: list) -> str:
    """The report of a :class:`~omnikin.api.umbmark.UMBmarkReport` whose ``result.json`` is ``doc``."""
    s = doc["settings"]
    noise_floor = report.engine.has_noise_model  # else the floor is the nominal robot's in physics
    level = f"{s['confidence_level'] * 100:g} %"
    built = (
        f"the robot file {s['true_robot']}"
        if s["true_robot"]
        else f"the nominal model with a draw of the {s['errors']!r} systematic error profile (seed {s['seed']})"
    )
    lines = [
        f"# UMBmark report: {report.robot.name}",
        "",
        f"Robot as built: {built}. "
        + (
            f"Engine: physics (MuJoCo at a {s['step'] * 1e3:g} ms time step, rollers and motors; no random error "
            "model: slip comes from the contacts)."
            if not noise_floor
            else f"Random errors: {s['noise']!r} profile."
        )
        + f" {s['runs']} runs per direction on a "
        f"{s['side']:g} m square, {s['mode']} mode, encoders sampled at {s['rate']:g} Hz"
        + (f", {s['trials']} procedures (Monte Carlo)." if s["trials"] > 1 else "."),
        "",
        f"Reproduce: `{report.command_line()}`.",
        "",
        "## Procedure",
        "",
        '1. UMBmark (Borenstein and Feng, "Measurement and correction of systematic odometry errors in mobile '
        'robots", 1996): the robot drives each square by its own (nominal) model, so its odometry says it '
        "returned home; the return error of a run is the true end pose minus the odometry end pose, "
        "E_max,syst the larger distance of the two directions' centres of gravity from the origin.",
    ]
    if s["calibrate"] and "calibration" not in doc:  # the fit failed (physics: runs that did not drive)
        lines += [
            "2. Calibration: the recommended runs were driven, but no robot of this layout explains them (the "
            "least-squares fit went out of range; below); no UMBmark after calibration.",
        ]
    elif s["calibrate"]:
        cal = doc["calibration"]
        lines += [
            f"2. Calibration: the {len(cal['paths'])} recommended runs ({', '.join(cal['paths'])}), each "
            f"driven {cal['repeats']} times by the nominal model with its end pose measured, and a "
            f"least-squares fit of {len(cal['parameters'])} wheel parameters "
            "(`omnikin calibrate`; the runs are in `calibration_runs.csv`).",
            "3. UMBmark again, the robot driven by its calibrated model.",
        ]
    else:
        lines += ["2. No calibration (`--no-calibrate`)."]
    floor_name = "noise floor" if noise_floor else "floor"
    lines += [
        f"{'4' if s['calibrate'] else '3'}. The {floor_name}: {doc['methods']['noise_floor']}.",
        "",
        "## Results",
        "",
    ]
    troubled = doc.get("physics_problems", [])
    if troubled:
        lines += [
            f'**{len(troubled)} runs did not drive as commanded** (docs/physics.md, "Runs that do not drive as '
            'commanded"); their end poses are in the numbers below as if they were odometry errors:',
            "",
            *[f"- {p[:400]}" for p in troubled],
            "",
        ]
    lines += [
        f"| | r_cg cw [mm] | r_cg ccw [mm] | E_max,syst [mm] | {level} interval [mm] | at the {floor_name} |",
        "|---|---:|---:|---:|---:|:---:|",
    ]
    for key, label in (("before", "before"), ("after", "after calibration")):
        if key in doc:
            d = doc[key]
            lines.append(
                f"| {label} | {mm_text(d['cw']['r_cg'])} | {mm_text(d['ccw']['r_cg'])} | {mm_text(d['e_max_syst'])} | "
                f"{_interval_mm(d['e_max_syst_interval'])} | {'yes' if d['at_noise_floor'] else 'no'} |"
            )
    floor = doc["noise_floor"]
    if not noise_floor:
        lines += [
            "",
            "Floor: the nominal robot (no systematic errors) driven by its own model in the physics engine shows "
            f"{physics_floor_text(floor, level)}: what the roller contact alone gives. A value up to "
            f"{mm_text(floor['e_max_syst_limit'])} mm cannot be told from it.",
        ]
    else:
        lines += [
            "",
            f"Noise floor: a perfectly calibrated robot shows E_max,syst of {mm_text(floor['e_max_syst_median'])} "
            f"mm (median) and up to {mm_text(floor['e_max_syst_p95'])} mm (95th percentile) over "
            f"{floor['procedures']} procedures "
            "with these random errors; a value at or below the 95th percentile cannot be told from a perfect "
            "calibration.",
        ]
    for key, label in (("before", "Before calibration"), ("after", "After calibration")):
        if key in doc and doc[key]["at_noise_floor"]:
            lines += [
                "",
                (
                    f"**{label}, E_max,syst ({mm_text(doc[key]['e_max_syst'])} mm) is at or below the floor**: "
                    "no larger than the roller contact alone gives the nominal robot."
                    if not noise_floor
                    else f"**{label}, E_max,syst ({mm_text(doc[key]['e_max_syst'])} mm) is at the noise floor**: "
                    "the systematic error left is below what UMBmark with this many runs can detect."
                ),
            ]
    if "after" in doc:
        ri = doc["reduction_factor_interval"]
        ri_text = f"{ratio_text(ri[0])} to {ratio_text(ri[1])}" if ri else "n/a (needs 3 runs per direction)"
        limit = floor_limit(doc)
        factor = reduction_text(doc["before"]["e_max_syst"], doc["after"]["e_max_syst"], limit)
        if reduction_bounded(doc["after"]["e_max_syst"], limit):
            below = (
                f"at or below the {floor_name} ({mm_text(limit)} mm)"
                if limit >= RESOLUTION
                else f"below {mm_text(RESOLUTION)} mm, what this report resolves"
            )
            lines += [
                "",
                f"Reduction factor of E_max,syst: {factor}. A bound: after calibration E_max,syst is {below}, "
                "so the factor is at least E_max,syst before over that limit (no interval: it has no upper end).",
            ]
        else:
            lines += [
                "",
                f"Reduction factor of E_max,syst: {factor} ({level} interval {ri_text})."
                + (
                    " The upper end is unbounded because the value after calibration is consistent with zero."
                    if ri and ri[1] is None
                    else ""
                ),
            ]
    sysm = doc["systematic"]
    lines += [
        "",
        "Without random errors (the systematic part alone): E_max,syst "
        f"{mm_text(sysm['e_max_syst_before'])} mm before"
        + (
            f", {mm_text(sysm['e_max_syst_after'])} mm after calibration "
            f"(reduction {reduction_text(sysm['e_max_syst_before'], sysm['e_max_syst_after'])}"
            + (
                f": below {mm_text(RESOLUTION)} mm after calibration is past what this report resolves)."
                if reduction_bounded(sysm["e_max_syst_after"])
                else ")."
            )
            if "e_max_syst_after" in sysm
            else "."
        ),
    ]
    lines += [
        "",
        "Intervals: "
        + doc["methods"]["e_max_syst_interval"]
        + "; reduction factor: "
        + doc["methods"]["reduction_factor_interval"]
        + ".",
    ]
    if "calibration" in doc:
        lines += _calibration_lines(report, doc)
    bor = report.before[0].borenstein
    if bor is not None:
        lines += [
            "",
            f"Borenstein's differential-drive figures (before): {bor.describe()}.",
        ]
    if "monte_carlo" in doc:
        lines += [
            "",
            "## Monte Carlo",
            "",
            "| | procedures | median [mm] | mean [mm] | 95th percentile [mm] |",
            "|---|---:|---:|---:|---:|",
        ]
        for label, st in doc["monte_carlo"].items():
            lines.append(
                f"| {label} | {st['procedures']} | {mm_text(st['e_max_syst_median'])} | "
                f"{mm_text(st['e_max_syst_mean'])} | {mm_text(st['e_max_syst_p95'])} |"
            )
    if figures:
        lines += ["", "## Figures", ""] + [f"![{f}]({f})" for f in figures]
    else:
        lines += ["", "No figures: they need matplotlib (pip install 'omnikin[viz]')."]
    lines += [
        "",
        "## Files",
        "",
        "- `result.json`: every number above (lengths in metres; `units` names the unit "
        "of every key, `methods` how each quantity is defined).",
        "- `true_robot.yaml`: the robot as built.",
        f"- `measurements_before.csv`: the runs of the first procedure before calibration "
        f"(`omnikin umbmark analyze measurements_before.csv --robot {report.robot.name} --side {s['side']:g}`).",
    ]
    if "calibration" in doc:
        lines += [
            "- `measurements_after.csv`: the same after calibration.",
            "- `calibrated_robot.yaml`: the calibrated robot.",
            f"- `calibration_runs.csv`: the calibration runs (`omnikin calibrate {report.robot.name} "
            "calibration_runs.csv -o calibrated.yaml`).",
        ]
    return "\n".join(lines) + "\n"


def _calibration_lines(report, doc) -> list:
    cal = doc["calibration"]
    lines = [
        "",
        "## Calibration",
        "",
        f"Residual RMS {cal['residual_rms_before']:.3g} -> {cal['residual_rms_after']:.3g} measurement sigmas "
        "over "
        f"{cal['runs']} runs.",
    ]
    if not cal["fits"]:
        lines += [
            "",
            f"**The calibration does not fit its runs** (residual RMS {cal['residual_rms_after']:.3g} "
            "measurement sigmas): the model cannot explain the measurements; do not use the calibrated "
            "robot.",
        ]
    lines += ["", "| parameter | estimate | sigma | unit |", "|---|---:|---:|---|"]
    for p in cal["parameters"]:
        lines.append(f"| {p['name']} | {p['value']:.6g} | {p['sigma']:.3g} | {p['unit']} |")
    blind = cal["identifiability"]["blind"]
    if blind:
        lines += ["", "The calibration runs cannot see these parameter combinations (left at zero):"]
        for combo in blind:
            lines.append("- " + " + ".join(f"{c['weight']:+.2f} {c['parameter']}" for c in combo))
    if "borenstein_iterations" in doc:
        lines += [
            "",
            "Borenstein's E_d/E_b correction, for comparison, E_max,syst after each iteration [mm]: "
            + ", ".join(mm_text(v) for v in doc["borenstein_iterations"]),
        ]
    if "injected_errors" in doc:
        lines += [
            "",
            "Injected and estimated radius errors:",
            "",
            "| wheel | injected [%] | estimated [%] |",
            "|---|---:|---:|",
        ]
        for name, e in doc["injected_errors"].items():
            est = cal["errors"].get(name)
            if est is not None:
                lines.append(f"| {name} | {e['radius'] * 100:+.3f} | {est['radius'] * 100:+.3f} |")
    return lines
