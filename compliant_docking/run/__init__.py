"""One job, from a composed config to a finished run directory: the runner, the run
directory's files (:mod:`.rundir`), the console summary, provenance and atomic writes.
"""
