"""The logger: ``+logger=mlflow`` logs every job to MLflow (:mod:`.mlflow_callback`; the
``logger`` extra; docs/logger.md). ``+tracking=mlflow`` is its deprecated old spelling."""
