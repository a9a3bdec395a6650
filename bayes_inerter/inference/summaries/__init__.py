"""What a finished chain says: draws and tables, intervals, loops and figures.

The posterior's draws and arviz summary (:mod:`.results`), b's interval
(:mod:`.interval`), the run's end state and warnings (:mod:`.end_state`), the force
over a steady period, measured and predicted (:mod:`.loops`), and the figures
(:mod:`.plots`). It reads :mod:`..posterior` and :mod:`..sampling`; neither reads it.
"""
