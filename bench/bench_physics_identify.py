"""
Benchmark identification on the physics plant against the first paper's method.

Run with ``python bench/bench_physics_identify.py``. The plant (hydro_sdp.core.synthetic.physics,
presets config/physics_arm.yaml and physics_boom.yaml) is not an SDP model: spool
valve with overlap and orifice flow, cylinder and linkage, load, cushions, stops.
Its full-stroke constant-duty runs (40..100 % duty, both directions, 100 Hz) are
identified two ways in the same run:

* ``identify`` (hydro_sdp), default options;
* the paper's method: eq. (5) with a pure delay, fitted by Nelder-Mead on the
  output error (:func:`hydro_sdp.core.identification.paper_baseline.paper_model`, the objective
  of bench_identify.py's baseline, vectorised), given the same experiments and
  end stops.

Each model is evaluated (``evaluate``: per-record mean MAE, Table 2; and the
time-weighted MAE) on held-out data: (a) identified at high load, evaluated at
low load; (b) identified on 40/60/80/100 %, evaluated on 50/70/90 %. Printed:
both MAEs, their ratio (target >= 2) and the ratio of identification times.

"""

import time

from hydro_sdp.core.identification.evaluation import evaluate, mean_errors
from hydro_sdp.core.identification.identify import identify
from hydro_sdp.core.identification.paper_baseline import paper_model
from hydro_sdp.core.synthetic.physics.plant import with_payload
from hydro_sdp.core.synthetic.physics.runs import full_stroke_runs
from hydro_sdp.io.documents import shipped_config
from hydro_sdp.io.plant_files import load_machine

DUTIES = (40, 50, 60, 70, 80, 90, 100)
PAYLOADS = {'arm': (250.0, 0.0), 'boom': (600.0, 0.0)}


def duty(record):
    """Return the duty magnitude of a full-stroke run, percent."""
    return abs(int(float(record.source.split()[-2])))


def timed(function):
    """Return ``(seconds, result)`` of one call."""
    started = time.perf_counter()
    result = function()
    return time.perf_counter() - started, result


def compare(label, fit, held_out):
    """Identify both ways on ``fit``, evaluate on ``held_out``, print a line; return the ratio."""
    ours_time, ours = timed(lambda: identify(fit))
    paper_time, paper = timed(lambda: paper_model(fit))
    mine = mean_errors(evaluate(held_out, ours.model))
    theirs = mean_errors(evaluate(held_out, paper))
    ratio = theirs['per_record']['model'] / mine['per_record']['model']
    print(f'  {label:30s} identify {mine["per_record"]["model"]:6.2f} deg '
          f'({mine["time_weighted"]["model"]:5.2f} time-weighted, {ours.model.kind}), '
          f'paper {theirs["per_record"]["model"]:6.2f} deg '
          f'({theirs["time_weighted"]["model"]:5.2f}): {ratio:4.1f}x better; '
          f'time {ours_time:5.1f} s vs {paper_time:5.1f} s ({ours_time / paper_time:.1f}x)')
    return ratio


def main():
    """Run the benchmark and print the figures."""
    ratios = []
    for joint, (high, low) in PAYLOADS.items():
        machine = load_machine(shipped_config(f'physics_{joint}.yaml'))
        heavy = full_stroke_runs(with_payload(machine, high), 0.01, DUTIES, seed=11)
        light = full_stroke_runs(with_payload(machine, low), 0.01, DUTIES, seed=29)
        print(f'{joint}: {len(heavy)} full-stroke runs per load, '
              f'{sum(len(r) for r in heavy):,} samples at 100 Hz')
        ratios.append(compare(f'load {high:g} kg -> {low:g} kg', heavy, light))
        ratios.append(compare('levels 40/60/80/100 -> 50/70/90',
                              [r for r in heavy if duty(r) in (40, 60, 80, 100)],
                              [r for r in heavy if duty(r) in (50, 70, 90)]))
    print(f'smallest accuracy ratio {min(ratios):.2f}x (target >= 2x), mean over records '
          '(Table 2)')


if __name__ == '__main__':
    main()
