"""Figures (matplotlib, Agg backend). Nothing outside this package imports matplotlib."""
import matplotlib

matplotlib.use("Agg")
