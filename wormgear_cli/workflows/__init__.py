"""Orchestration: one module per command that reads files, calls the core and builds the
command's document.  The CLI and the Python API both call these; the layers below never read
or write a file.
"""
