"""discrepancy: learn sparse discrepancy models that correct first-principles models."""
__version__ = "0.1.0"
