"""Hydra's config tree, shipped as the data package ``compliant_docking.conf`` (pyproject.toml
maps it to this folder). Nothing here is Python: this file only makes the folder findable
through the import system (compliant_docking.CONF_DIR) in an editable install and a wheel."""
