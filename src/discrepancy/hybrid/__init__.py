"""The hybrid model's parts that the model and the estimators share, knowing neither: its
equations as CasADi functions (:mod:`.casadi_form`), the input between samples
(:mod:`.inputs`) and what each recorded output measures (:mod:`.outputs`)."""
