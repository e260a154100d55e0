"""The bounds of the newer flags and fields, in one table, and the work a request implies,
estimated before it starts: a request over a cap is refused in well under a second with the number
it would take (exit 2), instead of running for hours. ``--help`` and docs/limits.md quote these.

Rates behind the estimates, measured on the project's 2-core machine (compiled in-house path,
DOP853, rtol 1e-7): a drive cycle takes about 1100 accepted steps per model second at the default
max_step 1e-3 s (2273 steps for 2 s at 1 Hz) and never fewer than duration / max_step; a seismic run
about 1400 per model second (4345 steps for 3.16 s of far-field 1, 5688 for 5 s of a 2 Hz harmonic),
about 2500 steps per second of wall time; ``nsd polar`` about 1.5 ms per quasi-static point.
"""
from __future__ import annotations

import math

from nsd_core.ground.motions import ROTATE_RANGE, SCALE_RANGE
from nsd_core.device.params import ParameterError

# ---- nsd seismic (and --set): the request's own flags
SEISMIC_DURATION_MAX = 300.0      # model seconds of one run (default: the input's own duration)
SEISMIC_SAMPLES_MAX = 2_000_000   # duration / dt_out: the output rows (the drive's cap too)
DT_OUT = (1e-6, 1.0)              # s
TIME_FACTOR = (0.01, 100.0)       # model seconds per record second
SCALE = SCALE_RANGE               # factor on the record's acceleration
ROTATE = ROTATE_RANGE             # deg
SCHEDULER_TIMEOUT = (0.1, 600.0)  # s, connect and handshake each
SCHEDULER_TIMEOUT_DEFAULT = 10.0

# ---- work caps: estimated steps of the in-house integrator
SEISMIC_STEPS_PER_SECOND = 1400   # measured (module docstring)
DRIVE_STEPS_PER_SECOND = 1100     # measured at max_step 1e-3 s (module docstring)
STEPS_MAX = 2_000_000             # one run: about 15 min of wall time on the 2-core machine
SWEEP_STEPS_MAX = 20_000_000      # a whole sweep, every design together

# ---- a building on the slab: the in-house engine's cost per model second grows with its stories (the
# generic evaluation of 10 + 2N bodies; measured, 2 loaded cores: 1.1, 2.3, 6.6, 11.5 wall s per model s at
# 3, 12, 25 and 50 stories); one run is held to RUN_WALL_MAX, like STEPS_MAX without a building
BUILDING_WALL_PER_STORY = 0.23    # wall s per model s per story
RUN_WALL_MAX = 900.0              # s, one run (about 15 min)

# ---- nsd ida: every run of every trace, estimated as nsd seismic's runs
IDA_STEPS_MAX = SWEEP_STEPS_MAX   # the whole study (about 2 h of CPU at ~2500 steps per wall second)

# ---- nsd polar
POLAR_STEP = (0.1, 90.0)          # deg, dividing 360
POLAR_POINTS = (64, 10_000)       # per cycle: below 64 the hysteresis steps overflow (NaN at 48, A = 25 mm)
POLAR_WIRES = (3, 64)
POLAR_DESIGNS_MAX = 16
POLAR_WORK_MAX = 200_000          # designs x azimuths x points per cycle: about 5 min on one core


def in_range(option: str, value, bounds: tuple[float, float], unit: str = "", low_open: bool = False) -> float:
    """A finite number in [low, high] (or (low, high] with ``low_open``), else one line naming it."""
    lo, hi = bounds
    ok = (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
          and (lo < value if low_open else lo <= value) and value <= hi)
    if not ok:
        raise ParameterError(f"{option} = {value}: must be a finite number in {'(' if low_open else '['}{lo:g}, "
                             f"{hi:g}]{' ' + unit if unit else ''}")
    return float(value)


def number(option: str, text) -> float:
    """A flag given as text (kept a string for a one-line message) as a float."""
    try:
        return float(text)
    except (TypeError, ValueError):
        raise ParameterError(f"{option} {text!r}: not a number") from None


def check_seismic_request(duration: float, dt_out: float, where: str = "") -> None:
    """Duration, output step, the samples they imply and the steps they would take, before any work."""
    tail = f" ({where})" if where else ""
    if not (math.isfinite(duration) and duration > 0):
        raise ParameterError(f"--duration = {duration}: must be a finite number > 0 s{tail}")
    if duration > SEISMIC_DURATION_MAX:
        steps = duration * SEISMIC_STEPS_PER_SECOND
        raise ParameterError(f"--duration = {duration:g} s{tail}: would take about {steps:.3g} solver steps "
                             f"(~{SEISMIC_STEPS_PER_SECOND} per model second); at most {SEISMIC_DURATION_MAX:g} s "
                             "(use --window or --duration for a part)")
    in_range("--dt-out", dt_out, DT_OUT, "s")
    if dt_out > duration:
        raise ParameterError(f"--dt-out = {dt_out:g}: must be <= the duration {duration:g} s{tail}")
    samples = duration / dt_out
    if samples > SEISMIC_SAMPLES_MAX:
        raise ParameterError(f"--dt-out = {dt_out:g}: {duration:g} s / {dt_out:g} s = {samples:.3g} output samples"
                             f"{tail}; at most {SEISMIC_SAMPLES_MAX:.0e} (a larger --dt-out or a shorter --duration)")


def drive_steps(duration: float, max_step: float | None) -> float:
    """Estimated accepted steps of one drive run on the in-house engine."""
    floor = duration / max_step if max_step else 0.0
    return max(duration * DRIVE_STEPS_PER_SECOND, floor)


def check_record_flags(args) -> None:
    """--scale, --rotate, --time-factor: finite numbers in their ranges (docs/limits.md), before any record is read."""
    from nsd_core.ground.motions import _number, _positive  # the record's own checks first (their wording)
    in_range("--scale", _positive("scale", args.scale), SCALE)
    in_range("--rotate", _number("rotate_deg", args.rotate), ROTATE, "deg")
    if args.time_factor is not None:
        in_range("--time-factor", number("--time-factor", args.time_factor), TIME_FACTOR)
    if args.duration is not None:
        check_seismic_request(args.duration, args.dt_out)
    else:
        in_range("--dt-out", args.dt_out, DT_OUT, "s")


def check_drive_work(duration: float, max_step: float | None, what: str = "this drive") -> float:
    steps = drive_steps(duration, max_step)
    if steps > STEPS_MAX:
        raise ParameterError(f"{what}: {duration:g} model seconds (cycles / frequency) would take about {steps:.3g} "
                             f"solver steps; at most {STEPS_MAX:.0e} (fewer --cycles, a higher --frequency or a "
                             "larger --max-step)")
    return steps


def check_polar_work(wires, step: float, points: int) -> None:
    if not wires or len(wires) > POLAR_DESIGNS_MAX:
        raise ParameterError(f"--wires: {len(wires)} designs; give 1 to {POLAR_DESIGNS_MAX}")
    if len(set(wires)) != len(wires):
        raise ParameterError(f"--wires {','.join(map(str, wires))}: each number once")
    for n in wires:
        if not POLAR_WIRES[0] <= n <= POLAR_WIRES[1]:
            raise ParameterError(f"--wires {n}: must be a whole number in [{POLAR_WIRES[0]}, {POLAR_WIRES[1]}]")
    in_range("--step", step, POLAR_STEP, "deg")
    turns = 360.0 / step
    if abs(turns - round(turns)) > 1e-9:
        raise ParameterError(f"--step = {step:g}: must divide 360 deg (e.g. 1, 5, 15, 22.5, 45)")
    if not POLAR_POINTS[0] <= points <= POLAR_POINTS[1]:
        raise ParameterError(f"--points-per-cycle = {points}: must be a whole number in [{POLAR_POINTS[0]}, "
                             f"{POLAR_POINTS[1]}] (fewer points let the hysteresis steps overflow)")
    work = len(wires) * round(turns) * points
    if work > POLAR_WORK_MAX:
        raise ParameterError(f"--step {step:g} x --points-per-cycle {points} x {len(wires)} designs: {work} "
                             f"quasi-static points (~{work * 1.5e-3:.0f} s of CPU); at most {POLAR_WORK_MAX}")


def building_factor(stories: int) -> float:
    """How many times a run with a building of ``stories`` costs what the step estimate assumes (~1400 steps
    per model second at ~2500 steps per wall second, 0.56 s; >= 1): 20 for 50 stories."""
    return max(1.0, BUILDING_WALL_PER_STORY * stories * 2500.0 / SEISMIC_STEPS_PER_SECOND) if stories else 1.0


def check_building_work(duration: float, stories: int, where: str = "") -> None:
    """One run of a structure with a building of ``stories``: its estimated wall time within RUN_WALL_MAX."""
    wall = duration * BUILDING_WALL_PER_STORY * stories
    if stories and wall > RUN_WALL_MAX:
        tail = f" ({where})" if where else ""
        raise ParameterError(f"--building stories={stories} over {duration:g} model s{tail}: about {wall / 60:.3g} min "
                             f"of wall time (~{BUILDING_WALL_PER_STORY * stories:.3g} s per model second); at most "
                             f"{RUN_WALL_MAX / 60:g} min (a shorter --duration or window, or fewer stories)")


def check_ida_work(durations: dict, runs: int, flag: str, stories: int = 0) -> float:
    """Before any run of ``nsd ida``: the study's estimated steps (records x 2 configurations x ``runs``
    runs x the record's model seconds x the seismic rate, times the building's cost factor) within
    IDA_STEPS_MAX, and each run's wall time (check_building_work). Returns the steps."""
    for rid, d in durations.items():
        check_building_work(d, stories, f"record {rid}")
    steps = sum(2 * runs * d * SEISMIC_STEPS_PER_SECOND for d in durations.values()) * building_factor(stories)
    if steps > IDA_STEPS_MAX:
        raise ParameterError(f"{flag}: {len(durations)} records x 2 configurations x {runs} runs of "
                             f"{sum(durations.values()) / len(durations):.3g} model s on average would take about "
                             f"{steps:.3g} solver steps; at most {IDA_STEPS_MAX:.0e} (fewer --records, levels or "
                             "--max-runs)")
    return steps


def check_ida_scales(im1: dict, first: list[float], flag: str, measure: str) -> None:
    """Each record's first levels (``first``: --levels, or [--start]) scale it within the record scale
    bound (nsd seismic --scale's)."""
    lo, hi = SCALE
    for rid, value in im1.items():
        for level in first:
            scale = level / value if value > 0 else math.inf
            if not lo <= scale <= hi:
                raise ParameterError(f"{flag} {level:g}: record {rid} would be scaled by {scale:.3g} (its {measure} at "
                                     f"scale 1 is {value:.4g} m/s^2); allowed: a scale in [{lo:g}, {hi:g}]")
