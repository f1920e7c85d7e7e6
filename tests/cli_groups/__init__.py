"""The groups of tests/cli_commands.py, one module each."""
