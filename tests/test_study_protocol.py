"""The study protocol (tenscell.studies.protocol): plans, named-column tables, execution with needs, estimates."""
import math

import pytest

from tenscell.fitting.models import MODELS, Population
from tenscell.fitting.models.base import Capabilities
from tenscell.studies.protocol import Check, Plan, StudyResult, Table, Task, execute, run_study


def _square(x):
    return x * x


def _add(a, b):
    return a + b


def _plan():
    return Plan("demo", {"n": 3}, (Task("a", "fit", _square, (3,)), Task("b", "fit", _square, (4,), weight=2.0),
                                   Task("c", "refit", _add, (), needs=("a", "b"))))


def test_plan_refuses_duplicate_keys_and_needs_out_of_order():
    with pytest.raises(ValueError, match="appears twice"):
        Plan("x", {}, (Task("a", "fit", _square, (1,)), Task("a", "fit", _square, (2,))))
    with pytest.raises(ValueError, match="needs 'b'"):
        Plan("x", {}, (Task("a", "fit", _add, (1,), needs=("b",)), Task("b", "fit", _square, (2,))))
    with pytest.raises(ValueError, match="weight"):
        Task("a", "fit", _square, (1,), weight=0)


def test_estimate_counts_every_task_by_kind():
    plan = _plan()
    assert plan.count() == 3 and plan.count("fit") == 2
    assert plan.kinds() == {"fit": 3.0, "refit": 1.0}
    assert plan.estimate_cpu({"fit": 2.0, "refit": 5.0}) == pytest.approx(11.0)
    with pytest.raises(KeyError, match="refit"):
        plan.estimate_cpu({"fit": 1.0})


@pytest.mark.parametrize("jobs", [1, 2])
def test_execute_passes_the_results_of_needs(jobs):
    lines = []
    results, records = execute(_plan(), jobs=jobs, rates={"fit": 0.1, "refit": 0.1}, notify=lines.append)
    assert results == {"a": 9, "b": 16, "c": 25}
    assert [r.key for r in records] == ["a", "b", "c"]
    assert all(r.cpu_s >= 0 and r.wall_s >= 0 for r in records)
    assert len(lines) == 3 and lines[-1].startswith("3/3 tasks")


def test_table_columns_are_named_not_positional():
    t = Table.from_records("m", [{"model": "a", "rms_decades": 0.1}, {"rms_decades": 0.2, "model": "b"}])
    assert t.columns == ("model", "rms_decades") and t.column("model") == ("a", "b")
    assert t.records()[1] == {"model": "b", "rms_decades": 0.2}
    with pytest.raises(ValueError, match="row 1 has no column 'rms_decades'"):
        Table.from_records("m", [{"model": "a", "rms_decades": 0.1}, {"model": "b"}])
    with pytest.raises(ValueError, match="unknown column 'x'"):
        Table.from_records("m", [{"model": "a"}, {"model": "b", "x": 1}])
    with pytest.raises(ValueError, match="appears twice"):
        Table("m", ("a", "a"), ())


class _Demo:
    name = "demo"

    def plan(self, options):
        return _plan()

    def assemble(self, plan, results):
        rows = [{"task": k, "value": v} for k, v in results.items()]
        return StudyResult(study=self.name, tables=(Table.from_records("demo", rows),),
                           checks=(Check("c is 25", results["c"] == 25),), data=results)


def test_run_study_records_what_each_task_cost():
    out = run_study(_Demo(), {})
    assert out.table("demo").column("value") == (9, 16, 25)
    assert out.checks[0].met and len(out.tasks) == 3 and math.isfinite(out.elapsed_s)
    assert out.files() == ("demo.csv",)


def test_every_model_declares_its_capabilities():
    for name, model in MODELS.items():
        caps = model.capabilities
        assert isinstance(caps, Capabilities), name
        assert caps.fits("moduli"), name
        assert caps.structural == model.structural, name
        assert caps.lumped_terms == (model.formula() is not None), name
    pop = Population("springpot+visc").capabilities
    assert pop.per_cell and not pop.structure_shares
    with pytest.raises(ValueError, match="data_kinds"):
        Capabilities(data_kinds=frozenset({"stress"}))


# ---- options, calibration and the estimate ------------------------------------------------------------------
from tenscell.studies.protocol import FIGURE, Machine, calibrate, flag, study_options  # noqa: E402


def test_a_study_takes_its_own_options_and_refuses_others_in_flag_syntax():
    class S:
        name, options = "s", {"draws": 200, "from_fit": None}

    assert study_options(S(), {"draws": 3}) == {"draws": 3, "from_fit": None}
    with pytest.raises(ValueError, match="--data-dir: study s takes no such option .*--draws, --from-fit"):
        study_options(S(), {"data_dir": "x"})
    assert flag("time_domain") == "--time-domain"


def test_the_share_of_a_cpu_follows_fair_sharing():
    quiet = Machine(cpus=2, others=0.0)
    assert quiet.share(1) == 1.0 and quiet.share(2) == 1.0 and quiet.share(4) == 0.5
    busy = Machine(cpus=2, others=6.0)
    assert busy.share(1) == pytest.approx(2 / 7) and busy.share(2) == pytest.approx(0.25)


def test_a_starved_calibration_implies_the_demand_of_the_others():
    from tenscell._parallel import CpuUse

    # a quarter of a CPU while 2 CPUs were all busy: fair sharing means 7 others wanted them
    m = Machine.measure(CpuUse(wall_s=1.0, cpu_s=0.25, cpus=2, busy_elsewhere=1.75, source="/proc/stat"))
    assert m.others == pytest.approx(7.0) and m.share(1) == pytest.approx(0.25)
    # a whole CPU: only what the others used counts
    m = Machine.measure(CpuUse(wall_s=1.0, cpu_s=1.0, cpus=2, busy_elsewhere=0.5, source="/proc/stat"))
    assert m.others == pytest.approx(0.5)


def test_the_wall_estimate_goes_wave_by_wave_over_the_workers():
    tasks = [Task(f"f{i}", "fit", _square, (i,)) for i in range(4)] + [Task("c", "refit", _add, (), needs=("f0", "f1"),
                                                                            weight=3.0)]
    plan = Plan("demo", {}, tasks, jobs=2, figures=2.0)
    rates = {"fit": 1.0, "refit": 2.0, FIGURE: 0.5}
    # wave 1: four 1 s fits on two workers (2 s), wave 2: one 6 s refit, then two figure units in this process
    assert plan.estimate_wall(rates) == pytest.approx(2.0 + 6.0 + 1.0)
    # others keep 2 CPUs busy: two workers of ours get half a CPU each, one gets two thirds
    assert plan.estimate_wall(rates, Machine(cpus=2, others=2.0)) == pytest.approx(4.0 + 9.0 + 1.5)
    with pytest.raises(KeyError, match="refit"):
        plan.estimate_wall({"fit": 1.0, FIGURE: 1.0})


def _spin(n):
    total = 0
    for k in range(n):
        total += k * k
    return total


def _set_up_then_spin(setup, n):
    _spin(setup)  # what the tasks do once (a problem built): not part of the rate
    return lambda: _spin(n)


def test_a_probe_that_returns_its_work_is_timed_without_its_setup():
    plain = Plan("demo", {}, [Task("a", "fit", _spin, (200_000,))],
                 calibration=[Task("probe", "fit", _spin, (200_000,))])
    set_up = Plan("demo", {}, [Task("a", "fit", _spin, (200_000,))],
                  calibration=[Task("probe", "fit", _set_up_then_spin, (4_000_000, 200_000))])
    rate, with_setup = calibrate(plain)[0]["fit"], calibrate(set_up)[0]["fit"]
    # the setup is 20 times the work: timed with it, the rate would be 21 times as large
    assert with_setup < 3 * rate


def test_calibration_rates_are_cpu_per_unit_of_weight():
    probe = Task("probe", "fit", _spin, (200_000,), weight=0.5)
    plan = Plan("demo", {}, [Task("a", "fit", _spin, (400_000,))], calibration=[probe])
    rates, machine = calibrate(plan)
    # the task does twice the probe's work: one unit is twice the probe, so the probe's weight is 0.5
    _, cpu, _ = __import__("tenscell.studies.protocol", fromlist=["_timed"])._timed(_spin, 400_000)
    assert rates["fit"] == pytest.approx(cpu, rel=0.6)
    assert 0 < machine.share(1) <= 1
    with pytest.raises(ValueError, match="needs no other task"):
        Plan("demo", {}, [], calibration=[Task("p", "fit", _add, (), needs=("a",))])
