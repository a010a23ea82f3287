"""Scale-out: the load matrix gives the same table on local processes and on a Dask cluster."""
import pytest

from fem.stiffness import save
from geometry.params import load_case
from pipeline.cli import main
from pipeline.sweep import SchedulerError, check_scheduler, chunks, run_tasks
from tests.support import case_path, stiffness_for_tests


def _square(x, y):
    return x * x + y


def test_tasks_come_back_in_order_locally_and_in_one_process():
    tasks = [(i, 1) for i in range(7)]
    assert run_tasks(_square, tasks, workers=2) == run_tasks(_square, tasks, workers=1) == \
        [i * i + 1 for i in range(7)]


def test_chunks_cover_every_item_once_in_order():
    assert chunks(range(10), 3) == [[0, 1, 2, 3], [4, 5, 6], [7, 8, 9]]
    assert chunks(range(2), 5) == [[0], [1]]


def test_the_matrix_on_a_loopback_dask_cluster_equals_the_local_run(tmp_path):
    distributed = pytest.importorskip("distributed")
    case = case_path("rv40e-81")
    stiff = tmp_path / "stiffness.json"
    save(stiffness_for_tests(load_case(case)), stiff)
    common = ["matrix", "--case", str(case), "--stiffness", str(stiff), "--duration", "2.2", "--quiet"]
    assert main([*common, "--out", str(tmp_path / "local")]) == 0
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        assert main([*common, "--out", str(tmp_path / "dask"), "--scheduler", cluster.scheduler_address]) == 0
    local = (tmp_path / "local" / "te_std.csv").read_text()
    assert local == (tmp_path / "dask" / "te_std.csv").read_text()
    assert local.splitlines()[0] == "torque_Nm,constant,square,sine"


def test_an_fe_sub_problem_on_a_loopback_dask_cluster_equals_the_local_run():
    # the fem stage maps its independent FE problems through run_tasks; the needle bearing is the
    # cheap one (seconds), enough to send real FE work through the cluster and compare
    distributed = pytest.importorskip("distributed")
    from fem.reduce import _compute, task_context
    case = load_case(case_path("rv40e-81"))
    task = [("needle_bearings", case, task_context(case))]
    local, = run_tasks(_compute, task)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        remote, = run_tasks(_compute, task, scheduler=cluster.scheduler_address)
    a, b = local.fields["turning_arm"], remote.fields["turning_arm"]
    for key in ("load_N", "deflection_m", "law_k_N_per_m_pow", "law_n"):
        # to round-off: a worker's BLAS may sum in another order (measured ~1e-15)
        assert getattr(a, key) == pytest.approx(getattr(b, key), rel=1e-12, abs=0), key


def _nap(seconds):
    import time
    time.sleep(seconds)
    return seconds


def _interrupt_at_first(i, n):
    raise KeyboardInterrupt   # what the CLI's signal handling delivers mid-sweep (Ctrl-C)


def test_an_interrupt_stops_the_local_pool_at_once_instead_of_running_every_task():
    import multiprocessing
    import time
    others = set(multiprocessing.active_children())   # what earlier tests may have left
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        run_tasks(_nap, [(1.0,)] * 8, workers=2, progress=_interrupt_at_first)
    assert time.perf_counter() - t0 < 3.0          # 8 x 1 s on 2 workers would be 4 s
    assert set(multiprocessing.active_children()) <= others   # no worker left running the rest


def _scheduler_tasks(dask_scheduler):
    return len(dask_scheduler.tasks)


def test_an_interrupt_cancels_the_pending_dask_tasks():
    distributed = pytest.importorskip("distributed")
    import time
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp://",
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        t0 = time.perf_counter()
        with pytest.raises(KeyboardInterrupt):
            run_tasks(_nap, [(0.5,)] * 10, scheduler=cluster.scheduler_address, progress=_interrupt_at_first)
        assert time.perf_counter() - t0 < 3.0      # 10 x 0.5 s on one thread would be 5 s
        with distributed.Client(cluster.scheduler_address) as client:
            deadline = time.time() + 10            # the scheduler forgets the cancelled tasks
            while time.time() < deadline and client.run_on_scheduler(_scheduler_tasks):
                time.sleep(0.1)
            assert client.run_on_scheduler(_scheduler_tasks) == 0


@pytest.mark.parametrize("address", ["tcp://127.0.0.1:8786", "127.0.0.1:8786", "tls://sched.example:8786",
                                     "tcp://[::1]:8786"])
def test_a_scheduler_address_of_the_usual_forms_is_accepted(address):
    assert check_scheduler(address) == address


@pytest.mark.parametrize("address", ["my-cluster", "http://host:8786", "tcp://host", "tcp://host:port"])
def test_a_malformed_scheduler_address_is_refused_with_the_allowed_form(address):
    with pytest.raises(SchedulerError, match="tcp://HOST:PORT"):
        check_scheduler(address)


def _deaf_to_sigterm(seconds):
    import signal
    import time
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    time.sleep(seconds)


def test_a_worker_that_outlives_sigterm_is_killed_and_a_finished_pool_leaves_no_worker():
    """sweep._end: SIGTERM, then SIGKILL for a process still alive 5 s later (a worker that
    inherited a SIGTERM handler, or one blocked for ever on a dead sibling's queue lock); a pool
    whose every result is in is ended the same way after its grace (no hang at shutdown)."""
    import multiprocessing
    import time
    from pipeline.sweep import _end
    others = set(multiprocessing.active_children())
    p = multiprocessing.get_context("fork").Process(target=_deaf_to_sigterm, args=(60.0,))
    p.start()
    time.sleep(0.5)
    t0 = time.perf_counter()
    _end([p])
    assert not p.is_alive() and p.exitcode == -9 and time.perf_counter() - t0 < 15.0
    assert run_tasks(_nap, [(0.01,)] * 4, workers=2) == [0.01] * 4
    assert set(multiprocessing.active_children()) <= others
