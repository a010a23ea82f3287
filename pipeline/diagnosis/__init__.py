"""Measured-data diagnosis: what the simulation gets wrong, which physical cause explains it, and
how much better the model gets with that cause (DESIGN.md "Measured data and diagnosis").

Flow (pure kernels, I/O at the edges):
  records (pipeline.records.read_record) -> zeros.group_records (encoder-zero groups)
  -> compare.residuals (measured - simulated TE, time and orders)
  -> signatures.build_library (each error source alone at unit size, through the model)
  -> fit.match (weighted least squares of the residual's order lines and zero-group means on the
     library, likelihood-ratio significance against the records' own noise floor)
  -> extension.extend (named causes -> model parameters, re-simulate, gain, holdout gain)
  -> report.write_report (diagnosis.json + off-screen index.html).

Cause ids: output_coaxiality, crank_eccentricity_error (disc-1 eccentric error: a zp x line; its
evidence warns that a one-disc tooth or crank-hole pattern error shares that order),
crank_hole_position_error (both discs: 2 zp x), torsional_stiffness, backlash.
"""
