"""``bench/lens_bench.py``: the lens a search picks from a grid, the free-focal row leaving the solve's
settings as they were, and a whole run's summary."""

import numpy as np
import pytest


@pytest.fixture(scope="module")
def bench(load_bench):
    return load_bench("lens_bench.py")


def test_the_search_refines_the_lowest_grid_point_by_a_parabola_in_log_focal(bench):
    grid = [20.0, 40.0, 80.0]
    # values of a parabola in log focal whose lowest point is at 50 mm: found exactly
    values = [(np.log(f) - np.log(50.0)) ** 2 for f in grid]
    assert bench.searched_focal(grid, values) == pytest.approx(50.0)
    assert bench.searched_focal(grid, [3.0, 2.0, 1.0]) == 80.0              # lowest at the grid's end: kept
    assert bench.searched_focal(grid, [1.0, 1.0, 1.0]) == 20.0              # flat: the first lowest, unrefined
    assert 20.0 < bench.searched_focal(grid, [1.5, 1.0, 3.0]) < 40.0        # leans to the lower neighbour


def test_the_free_focal_row_puts_the_solves_settings_back(bench, monkeypatch):
    from core.joint_solve import pipeline

    before = (pipeline.UNDETERMINED_FOCAL_SIGMA, pipeline.PAPER_CAMERA_SIGMA, pipeline.STILL_CAMERA_SIGMA)
    seen = []

    def failing(tracks, truth, focal_mm):
        seen.append((pipeline.UNDETERMINED_FOCAL_SIGMA, pipeline.PAPER_CAMERA_SIGMA[1],
                     pipeline.STILL_CAMERA_SIGMA[1]))
        raise RuntimeError("a solve that fails")

    monkeypatch.setattr(bench, "solve", failing)
    with pytest.raises(RuntimeError):
        bench.free_focal_solve(None, None)
    assert seen == [(bench.FREE_SIGMA,) * 3]
    assert (pipeline.UNDETERMINED_FOCAL_SIGMA, pipeline.PAPER_CAMERA_SIGMA, pipeline.STILL_CAMERA_SIGMA) == before


def test_a_run_prints_each_lens_and_the_summary(bench, capsys):
    assert bench.main(["builtin:stand", "--no-builtins", "--scenario", "still", "--half", "all", "--max-s", "2",
                       "--factors", "0.71,1", "--search", "30,45,70", "--free-focal"]) == 0
    text = capsys.readouterr().out
    for label in ("assumed:", "0.71x:", "1x:", "searched:", "free:"):
        assert label in text
    assert "| searched by lifter |" in text and "searched lens over the true" in text
    assert "reproj: minimum at 0.71x" in text


def test_bad_grids_are_refused_in_one_line(bench, capsys):
    with pytest.raises(SystemExit):
        bench.main(["builtin:stand", "--search", "30,45"])
    assert "three or more" in capsys.readouterr().err
