"""Settings of the prediction-error experiment, shared by the run and its report: the true
discrepancy's terms, the sample time and record lengths (s), and the push and noise levels."""
TRUE = {"vel": -0.3, "pos^3": -0.5}
DT, T_FULL, T_QUICK = 0.05, 300.0, 75.0    # quick: for the tests only
PUSH_STD, PUSH_EVERY, PROCESS_NOISE, SENSOR_NOISE = 0.5, 15.0, 0.02, 0.01
