"""The output-error path's choice: the library's one-standard-error rule on held-out errors."""
import numpy as np

from discrepancy.models.outputs.output_fit import SupportScore, choose


def _score(n_terms, mse, se):
    support = np.zeros((1, 4), bool)
    support[0, :n_terms] = True
    return SupportScore(support, support.astype(float), mse, se)


PATH = [_score(4, 1.00, 0.10), _score(3, 0.95, 0.05), _score(2, 1.02, 0.30), _score(1, 1.5, 0.1),
        _score(0, 3.0, 0.2)]


def test_the_sparsest_support_within_one_standard_error_of_the_best():
    # best: 3 terms at 0.95 +- 0.05, so the bar is 1.00: the 4-term support (1.00) is inside,
    # the 2-term one (1.02) is not, whatever its own standard error
    assert choose(PATH, None).n_terms == 3
    wider = [*PATH[:1], _score(3, 0.95, 0.08), *PATH[2:]]
    assert choose(wider, None).n_terms == 2


def test_a_relative_tolerance_on_the_rms_error_replaces_the_rule():
    # RMS: best sqrt(0.95) = 0.975; 10 % above is 1.072 >= sqrt(1.02) = 1.010 but < sqrt(1.5)
    assert choose(PATH, 0.10).n_terms == 2
