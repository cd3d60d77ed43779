"""The hybrid model's parts that the model and the estimators share, knowing neither: its
equations as CasADi functions (:mod:`discrepancy.hybrid.casadi_form`), the input between
samples (:mod:`discrepancy.hybrid.inputs`), what each recorded output measures
(:mod:`discrepancy.hybrid.outputs`), and CasADi functions compiled to C and cached
(:mod:`discrepancy.hybrid.codegen`)."""
