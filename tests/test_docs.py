"""The documentation's machinery: which pages the API reference must have (docs/_ext). The
README's and the user guide's code blocks run in tests/test_readme.py."""
import sys
from pathlib import Path

import pytest

import discrepancy as dc

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
api_catalogue = pytest.importorskip("api_catalogue")  # needs sphinx: the [docs] extra


@pytest.fixture(scope="module")
def catalogue():
    return api_catalogue.Catalogue("discrepancy")


def test_every_name_of_the_package_all_lives_at_the_top(catalogue):
    for name in dc.__all__:
        obj = getattr(dc, name)
        expected = obj.__name__ if api_catalogue.kind_of(obj) == "module" else \
            f"discrepancy.{name}"
        assert catalogue.home_of(obj, name) == expected


def test_other_paths_resolve_to_the_one_page(catalogue):
    documented = api_catalogue.documented_name
    for path in ("discrepancy.models.DiscrepancyModel",
                 "discrepancy.models.discrepancy_model.DiscrepancyModel"):
        assert documented(catalogue, path) == "discrepancy.DiscrepancyModel"
    assert documented(catalogue, "discrepancy.models.discrepancy_model.DiscrepancyModel.fit") \
        == "discrepancy.DiscrepancyModel.fit"
    assert documented(catalogue, "discrepancy.fitting.setup.FitSetup") == \
        "discrepancy.models.FitSetup"
    assert documented(catalogue, "discrepancy.no_such_name") is None


def test_a_function_named_like_its_module_is_documented_where_it_is_defined(catalogue):
    # discrepancy.control.closed_loop is the module's name; the function lives one level down
    from discrepancy.control import closed_loop
    assert catalogue.home_of(closed_loop) == "discrepancy.control.closed_loop.closed_loop"
    assert "discrepancy.control.closed_loop" in catalogue.modules


def test_public_modules_and_names_follow_the_underscore_rule(catalogue):
    assert "discrepancy.models.discrepancy_model" in catalogue.modules
    assert not any(part.startswith("_") for m in catalogue.modules for part in m.split("."))
    exported = dict(catalogue.exported_entries("discrepancy.resources"))
    assert {"MEMORY_LIMIT", "MAX_FEATURES", "check_memory"} <= set(exported)
    # a constant documented with #: in a module without __all__ is public; one without is not
    resolution = {name for name, _ in
                  catalogue.exported_entries("discrepancy.differentiation.resolution")}
    assert "TOLERANCE" in resolution and "ROWS" not in resolution
