"""Robot models and interface fragments, shipped as the data package ``compliant_docking.assets``
(pyproject.toml maps it to this folder). Nothing here is Python: this file only makes the
folder findable through the import system (compliant_docking.ASSETS_DIR) in an editable install
and a wheel."""
