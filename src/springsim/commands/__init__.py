"""Subcommands of the `springsim` command line, one module each (see springsim.cli)."""
