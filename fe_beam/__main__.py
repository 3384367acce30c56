"""``python -m fe_beam ...``: the ``fe-beam`` command (`fe_beam.cli.main`). Importing this
module runs nothing (a tool that imports every module of the package, as tests/cross_stack.py
does, must not start the command line)."""

from fe_beam.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
