"""Experiment tracking: ``+tracking=mlflow`` logs every job to MLflow
(:mod:`.mlflow_callback`; the ``tracking`` extra; docs/tracking.md)."""
