"""The hybrid model's parts that the model and the estimators share, knowing neither: its
equations as CasADi functions (:mod:`discrepancy.hybrid.casadi_form`), the input between
samples (:mod:`discrepancy.hybrid.inputs`) and what each recorded output measures
(:mod:`discrepancy.hybrid.outputs`)."""
