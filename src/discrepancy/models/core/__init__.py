"""The model's parts below the class: its set-up resolution, term choice and constraints, names,
argument checks, conditioning, scoring, bootstrap uncertainty, and its PySINDy and
prediction-error faces."""
