"""
Benchmark the discrepancy workflow.

Run with ``make bench`` or ``python bench/bench_diagnose.py``. Prints the time to
diagnose a 5-minute 100 Hz record with the whole vocabulary (target: under 5 s),
for a J2 joint with a valve lag the model lacks and for one with nothing missing,
against the time to simulate the record once (the unit of work every candidate
repeats).

"""

import time

from hydro_sdp.core.diagnosis import diagnose, VOCABULARY
from hydro_sdp.core.model.effects import ValveLag
from hydro_sdp.core.model.simulation import simulate
from hydro_sdp.core.synthetic.joint_experiments import experiment_record
from hydro_sdp.io.model_files import default_model_path, load_model


def main():
    """Run the benchmark and print the figures."""
    model = load_model(default_model_path())
    print(f'diagnosing a 5-minute 100 Hz record with all {len(VOCABULARY)} effects')
    for label, truth in (('valve lag missing', model.with_effect(ValveLag(0.15))),
                         ('nothing missing', model)):
        record = experiment_record(truth, 'random', seed=3, duration=300.0)
        validation = experiment_record(truth, 'random', seed=4, duration=60.0)
        started = time.perf_counter()
        result = diagnose([record], model, validation=[validation])
        took = time.perf_counter() - started
        started = time.perf_counter()
        simulate(model, record.v, 0.01, float(record.y[0]))
        once = time.perf_counter() - started
        print(f'  {label:18s}: {took:5.1f} s (target < 5 s), named {result.effect}, '
              f'{len(result.rounds)} rounds; one simulation takes {1e3 * once:.1f} ms '
              f'({took / once:,.0f} simulations worth)')


if __name__ == '__main__':
    main()
