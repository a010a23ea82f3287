"""Measured-data diagnosis: what the simulation gets wrong, which physical cause explains it, and
how much better the model gets with that cause (DESIGN.md "Measured data and diagnosis").

Flow (pure kernels, I/O at the edges):
  records (dynamics.records.read_records: split where the motion reverses)
  -> diagnose.diagnose: input checks (inputs.py: ratio, time unit, glitches masked, gaps), zero
     groups (zeros.py), residuals (measured - simulated TE, simulate.py), the signature library
     (signatures.py: each registered cause alone at unit size, through the model), fit.match
     (weighted least squares of the residual's order lines and zero-group means on the library,
     likelihood-ratio significance against the records' own noise floor), the extension
     (extension.py: named causes -> model parameters within their physical bounds, re-simulate,
     gain, holdout gain; causes on a bound or below the noise floor dropped), what is left
     unexplained (unexplained.py)
  -> report.write_report (diagnosis.json + off-screen index.html; notes one line each).

Causes: one module each under causes/, listed by the registry `causes.CAUSES` (its docstring,
`python -c "import pipeline.diagnosis.causes as c; print(c.__doc__)"`, lists them from the
registry); bench.py hides any cause with a `draw` in the virtual bench.
"""
