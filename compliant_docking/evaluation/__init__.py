"""What a run is judged by: the registry of reported metrics (:mod:`.registry`), the
docking metrics, seat state and docking gate (:mod:`.docking`), and the free-space
tracking gate (:mod:`.tracking_gate`). Computed after the loop from the time series.
"""
