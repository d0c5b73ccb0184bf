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
