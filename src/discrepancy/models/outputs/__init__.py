"""Output-error fitting: the multiple-shooting objective and problem, the fit and refit of a model
to measured outputs, their checks and the model's output-error methods."""
