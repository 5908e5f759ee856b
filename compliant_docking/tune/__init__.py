"""Gain tuning with Optuna as a Hydra sweeper (``hydra/sweeper=optuna``, ``+experiment=tune``).

- :mod:`.sweeper`: the ask-and-tell loop (trials in batches through the launcher);
- :mod:`.space`: the search space and the draws, in Hydra's override grammar;
- :mod:`.objectives`: what a trial scores, penalties, the registry of objectives;
- :mod:`.study`: the sampler, the SQLite study in the sweep directory, resuming it;
- :mod:`.outputs`, :mod:`.figures`: trials table, best parameters, ready YAML, figures.

Optuna is the ``tune`` extra (``pip install -e '.[tune]'``); docs/tuning.md.
"""
