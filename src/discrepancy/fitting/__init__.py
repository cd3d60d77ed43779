"""Data -> Gram statistics: the frozen set-up, the regression rows, accumulation in blocks,
chunk streams and Dask. Below the models: it knows no model class (a model passes its
``make_setup`` down)."""
