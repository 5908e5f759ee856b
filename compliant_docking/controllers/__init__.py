"""Controllers: one module per ``controller=`` option, shared pieces in :mod:`.base`."""
