"""The error every layer raises for bad user input (a case, a parameter, a file, a command)."""


class InputError(ValueError):
    """Bad user input: the CLI prints the one-line message and exits with code 2."""
