"""Running a fitted model forward: continuous simulation, k-step prediction, the compiled CasADi
stepper, discrete-time iteration, simulation options and the fitted region guard."""
