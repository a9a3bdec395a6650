"""The posterior: what a record says about the parameters, before any sampling.

The priors (:mod:`.priors`), the likelihoods' settings (:mod:`.likelihood`) and their
forms (the time-domain residual in :mod:`.model`; :mod:`.harmonic`; motion in, force out
in :mod:`.motion`, with the reversals' and the friction law's deviations marginalised in
:mod:`.reversals` and :mod:`.friction_law`, the discrepancy in :mod:`.discrepancy`), the
richer models' effects (:mod:`.effects`), the impedance map (:mod:`.impedance`), and the
log posterior of one record (:mod:`.model`) or of many (:mod:`.joint`). Nothing here
samples; :mod:`..sampling` does, and :mod:`..summaries` reads what it drew.
"""
