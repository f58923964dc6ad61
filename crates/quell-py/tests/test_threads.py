"""simulate releases the GIL: two threads run simulations at the same time.

Load-robust form of "two threads finish four runs in well under four runs' time": each run's own
wall time is measured inside its thread; if the runs held the GIL they could not overlap, and the
four runs would take at least the sum of their durations. With the GIL released they overlap, so
the total is close to half the sum on two free cores (this machine has 2). The bound 0.8 leaves
room for other processes on the machine, and a run is long enough (≈ 0.1 s) to dwarf thread start-up."""

import os
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

import quell


def timed_run(scenario):
    start = time.perf_counter()
    r = quell.simulate(scenario, t_end=1000.0, output_step=1.0)
    return time.perf_counter() - start, r


def test_two_threads_run_four_simulations_in_parallel():
    assert (os.cpu_count() or 1) >= 2, "this test needs two cores"
    s = quell.paper_example()
    timed_run(s)  # the design is computed and cached on the first run
    start = time.perf_counter()
    with ThreadPoolExecutor(max_workers=2) as pool:
        runs = list(pool.map(timed_run, [s] * 4))
    total = time.perf_counter() - start
    busy = sum(d for d, _ in runs)
    assert all(r.outcome["status"] == "completed" for _, r in runs)
    assert total < 0.8 * busy, f"4 runs took {total:.3f} s in 2 threads; their own durations add to {busy:.3f} s"
    # The runs are the same computation: threads do not disturb each other's results.
    first = runs[0][1]
    assert all((r.y == first.y).all() for _, r in runs)


@pytest.mark.parametrize(
    "output_step, sample_time", [(1.0, None), (1e5, None), (1e5, 1e-3)], ids=["rows", "one-row", "sampled-one-row"]
)
def test_ctrl_c_stops_a_running_simulation(python_child, output_step, sample_time):
    """SIGINT during simulate (GIL released, in Rust) raises KeyboardInterrupt within ~0.1 s, also
    when the run records no row before its end (output_step = t_end): the run reports its progress
    every 256 steps between rows (the library's PROGRESS_EVERY); before, such a run finished first."""
    import signal

    # The exception carries the samples up to the interruption, as a sweep's carries its rows.
    code = (
        "import quell\nprint('ready', flush=True)\n"
        "try:\n"
        f"    quell.simulate(quell.paper_example(), t_end=1e5, output_step={output_step}, sample_time={sample_time})\n"
        "except KeyboardInterrupt as e:\n"
        "    r = e.result\n    print('kept', len(r.t), r.outcome['status'], r.t[-1] <= r.outcome['t'], flush=True)\n"
        "    raise\n"
    )
    child = python_child(code)
    time.sleep(0.5)  # into the run, which takes tens of seconds
    sent = time.perf_counter()
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=120)
    assert "KeyboardInterrupt" in err, err
    kept = out.split("kept ")[1].split()
    rows = 1 if output_step == 1e5 else 2  # t = 0 at least, and more at one row a second
    assert int(kept[0]) >= rows and kept[1:] == ["interrupted", "True"], out
    # The interruption is noticed within 50 ms of Python's signal check and 256 steps (~2 ms);
    # 10 s leaves room for a loaded CI machine (the whole run takes minutes).
    assert time.perf_counter() - sent < 10


def test_ctrl_c_stops_simulations_in_worker_threads(python_child):
    """Python runs signal handlers in the main thread only: simulations in a ThreadPoolExecutor
    never saw Ctrl-C, and leaving the pool's `with` waited for them to run to their end. The package
    counts Ctrl-C for its calls in every thread: the workers' runs raise KeyboardInterrupt too, and
    the pool is left within seconds of SIGINT (each run alone takes about 35 s). A run started
    after the Ctrl-C is not affected."""
    import signal

    code = (
        "import time, quell\nfrom concurrent.futures import ThreadPoolExecutor\n"
        "s = quell.paper_example(); s.design()\n"
        "run = lambda _: quell.simulate(s, t_end=3e5, output_step=10.0)\n"
        "pool = ThreadPoolExecutor(max_workers=2)\n"
        "futures = [pool.submit(run, i) for i in range(2)]\n"
        "print('ready', flush=True)\n"
        "try:\n"
        "    while True:\n        time.sleep(0.01)\n"
        "except KeyboardInterrupt:\n"
        "    start = time.perf_counter()\n"
        "    pool.shutdown(wait=True)\n"
        "    kinds = sorted(type(f.exception()).__name__ for f in futures)\n"
        "    print('left', time.perf_counter() - start, *kinds, flush=True)\n"
        "    after = quell.simulate(s, t_end=1.0)\n"
        "    print('after', after.outcome['status'], flush=True)\n"
    )
    child = python_child(code)
    time.sleep(0.5)  # into the runs
    child.send_signal(signal.SIGINT)
    out, err = child.communicate(timeout=120)
    left = out.split("left ")[1].splitlines()[0].split()
    assert left[1:] == ["KeyboardInterrupt", "KeyboardInterrupt"], out + err
    # Noticed within 50 ms of a check; 10 s leaves room for a loaded CI machine.
    assert float(left[0]) < 10, out
    assert "after completed" in out, out + err


def test_one_controller_shared_by_threads_serializes_its_steps():
    """Eight threads step one Controller 500 times each with the same y and g (as tuples of numpy
    scalars, the slow reading path, and with a tiny switch interval to interleave them): no error
    (PyO3's "Already borrowed" before), and the state is that of 4000 steps taken in one thread."""
    import sys
    from concurrent.futures import ThreadPoolExecutor

    import numpy as np

    d = quell.paper_example().design()
    y, g = (np.float64(0.3), np.float64(-0.1)), (np.float64(1.0), np.float64(2.0))
    shared = quell.Controller(d, sample_time=1e-3)

    def work(_):
        for _ in range(500):
            shared.step(y, g)
            shared.eta()

    old = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        with ThreadPoolExecutor(8) as pool:
            list(pool.map(work, range(8)))
    finally:
        sys.setswitchinterval(old)
    alone = quell.Controller(d, sample_time=1e-3)
    for _ in range(4000):
        alone.step(y, g)
    np.testing.assert_array_equal(shared.eta(), alone.eta())
    np.testing.assert_array_equal(shared.x_hat(), alone.x_hat())


# A 500-state plant with two inputs and outputs, and 500 observer poles near its own.
LARGE_PLANT = (
    "import time, numpy as np, quell\n"
    "n = 500; rng = np.random.default_rng(1)\n"
    "G = rng.normal(size=(n, n)) * 0.3 / np.sqrt(n)\n"
    "A = -np.diag(1.0 + 0.05 * np.arange(n)) + (G + G.T) / 2\n"
    "B = rng.normal(size=(n, 2))\n"
    "p = quell.Plant(A, B, B.T.copy(), delays=[0.0, 0.0])\n"
    "poles = list(np.linalg.eigvalsh(A) - 0.3)\n"
)


def interrupted_cpu(python_child, call, setup=LARGE_PLANT, after=1.0):
    """Starts `call` after `setup` (LARGE_PLANT by default) in a child, sends SIGINT `after` seconds
    into it, and returns the CPU time the child spent in the call until KeyboardInterrupt reached it
    (CPU time, not wall time, so that load on the machine does not move the bound)."""
    import signal

    code = (
        setup + "print('ready', flush=True)\n"
        "start = time.process_time()\n"
        "try:\n"
        f"    {call}\n"
        "except KeyboardInterrupt:\n"
        "    print('cpu', time.process_time() - start, flush=True)\n"
        "    raise\n"
        "print('finished', flush=True)\n"
    )
    child = python_child(code)
    try:
        time.sleep(after)  # into the call
        child.send_signal(signal.SIGINT)
        out, err = child.communicate(timeout=300)  # the uninterrupted call takes ~1 min at load 10
    finally:
        child.kill()
    assert "KeyboardInterrupt" in err, err
    assert "finished" not in out
    assert "cpu" in out, f"KeyboardInterrupt did not come from the call: {out!r} {err[-400:]!r}"
    return float(out.split("cpu", 1)[1].split()[0])


def test_ctrl_c_stops_a_large_design(python_child):
    """SIGINT during quell.design of a 500-state plant (seconds of pole placement: 2 outputs place
    500 observer poles, which KNV0 sweeps and then refuses) raises KeyboardInterrupt promptly, not
    when the design returns.

    The whole design takes 15.9 s of CPU (50 s of wall time at load 10); interrupted 0.2 s to 3 s
    into it, the child had spent 1.1-1.8 s (the phases before KNV0's first poll of the stop flag,
    staircase and eigendecompositions, are the most of it; measured at load 10 with this test's
    code). 6 s tells an interrupted design from one that ran to its end with a wide margin on both
    sides; a design that ignored SIGINT would report its whole 15.9 s."""
    call = (
        "quell.design(p, observer_poles=poles, channel_poles=[[-2.0], [-3.0]], "
        "reference_filter_poles=[[-1.0], [-1.0]], mu=[1.0, 1.0], beta=1.0)"
    )
    cpu = interrupted_cpu(python_child, call)
    assert cpu < 6.0, f"KeyboardInterrupt came after {cpu:.1f} s of CPU in quell.design (the whole design: 15.9 s)"


def test_ctrl_c_stops_a_large_placement(python_child):
    """SIGINT during quell.place of the same 500 observer poles (A', C' = B') raises
    KeyboardInterrupt promptly. The whole placement takes about 20 s of CPU (refused at its end: the poles are too close)
    (measured with this test's code); it had ignored SIGINT until it returned."""
    cpu = interrupted_cpu(python_child, "quell.place(A.T, B, poles)")
    assert cpu < 6.0, f"KeyboardInterrupt came after {cpu:.1f} s of CPU in quell.place"


def test_ctrl_c_stops_a_studys_nominal_run(python_child):
    """SIGINT while quell.sweep_runs builds the first spec of a study with draws, which carries out
    the grid point's nominal run (t_end = 1e5 s: ~10 s of CPU), raises KeyboardInterrupt promptly:
    the nominal run took no stop signal and ran to its end (12.4 s measured)."""
    setup = (
        "import time, quell\n"
        "study = quell.Study(quell.paper_example(), simulation={'t_end': 1e5, 'output_step': 10.0},\n"
        "                    monte_carlo={'runs': 2, 'plant.x0': {'normal': 0.1}})\n"
    )
    cpu = interrupted_cpu(python_child, "list(quell.sweep_runs(study))", setup=setup, after=0.5)
    assert cpu < 4.0, f"KeyboardInterrupt came after {cpu:.1f} s of CPU (the nominal run alone: ~10 s)"


def test_ctrl_c_stops_the_check_of_a_large_grid(python_child):
    """SIGINT while quell.Study checks 10⁶ grid values (a design each: about a minute of CPU)
    raises KeyboardInterrupt promptly; the check had run to its end (71 s measured)."""
    setup = "import time, numpy as np, quell\nvalues = list(np.linspace(1.0, 100.0, 10**6))\n"
    call = "quell.Study(quell.paper_example(), grid={'design.mu[0]': values})"
    cpu = interrupted_cpu(python_child, call, setup=setup)
    assert cpu < 10.0, f"KeyboardInterrupt came after {cpu:.1f} s of CPU (the whole check: ~1 min)"


def test_ctrl_c_reaches_a_thread_waiting_for_a_shared_spec_iterator(python_child):
    """SIGINT while the main thread waits for its turn at a sweep_runs() iterator that a worker
    holds (carrying out a grid point's nominal run, ~10 s of CPU) raises KeyboardInterrupt
    promptly: the wait had been deaf to it until the worker's run ended (8.7 s; diff review)."""
    setup = (
        "import threading, time, quell\n"
        "study = quell.Study(quell.paper_example(), simulation={'t_end': 1e5, 'output_step': 10.0},\n"
        "                    monte_carlo={'runs': 2, 'plant.x0': {'normal': 0.1}})\n"
        "specs = quell.sweep_runs(study)\n"
        "def take():\n"
        "    try:\n"
        "        next(specs)\n"
        "    except KeyboardInterrupt:\n"
        "        pass\n"
        "threading.Thread(target=take, daemon=True).start()\n"
        "time.sleep(0.3)\n"
    )
    cpu = interrupted_cpu(python_child, "next(specs)", setup=setup, after=1.0)
    assert cpu < 5.0, f"KeyboardInterrupt came after {cpu:.1f} s of CPU (the worker's nominal run alone: ~10 s)"
