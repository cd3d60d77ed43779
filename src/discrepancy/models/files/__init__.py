"""A model on paper and on disk: symbolic export (sympy, LaTeX, CasADi) and versioned JSON model
files with their parameter codecs."""
