"""`discrepancy reproduce`, provided by this package through the library's entry point."""
import subprocess
import sys

import discrepancy_paper.cli as paper_cli
from discrepancy.cli import main
from discrepancy.errors import DataError


def test_reproduce_all_reports_a_failing_experiment_and_runs_the_rest(tmp_path, monkeypatch,
                                                                      capsys):
    ran = []

    def fine(out, *, quick=False):
        ran.append("fine")
        return tmp_path

    def broken(out, *, quick=False):
        raise DataError("data folder not found")

    monkeypatch.setattr(paper_cli, "EXPERIMENTS", {"a": None, "b": None, "c": None})
    monkeypatch.setattr(paper_cli, "get_experiment", lambda name: broken if name == "b" else fine)
    assert main(["reproduce", "all", "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert ran == ["fine", "fine"] and "[b] FAILED: data folder not found" in err
    assert "1 of 3 experiments failed: b" in err


def test_reproduce_is_found_by_the_library_and_runs_as_a_module():
    for command in ([sys.executable, "-m", "discrepancy.cli", "reproduce", "--help"],
                    [sys.executable, "-m", "discrepancy_paper", "reproduce", "--help"]):
        out = subprocess.run(command, capture_output=True, text=True, check=True).stdout
        assert "vdp-parameter" in out and "cart-swingup" in out
