"""Measured-data diagnosis: what the simulation gets wrong, which physical cause explains it, and
how much better the model gets with that cause (DESIGN.md "Measured data and diagnosis").

Flow (pure kernels, I/O at the edges):
  records (pipeline.records.read_record) -> zeros.group_records (encoder-zero groups)
  -> diagnose.diagnose: residuals (measured - simulated TE, simulate.py), the signature library
     (signatures.py: each registered cause alone at unit size, through the model), fit.match
     (weighted least squares of the residual's order lines and zero-group means on the library,
     likelihood-ratio significance against the records' own noise floor), the extension (named
     causes -> model parameters, re-simulate, gain, holdout gain)
  -> report.write_report (diagnosis.json + off-screen index.html).

Causes: one module each under causes/, listed by the registry `causes.CAUSES` (its docstring,
`python -c "import pipeline.diagnosis.causes as c; print(c.__doc__)"`, lists them from the
registry); bench.py hides any cause with a `draw` in the virtual bench.
"""
