"""``python -m fe_beam ...``: the ``fe-beam`` command (`fe_beam.cli.main`)."""

from fe_beam.cli import main

raise SystemExit(main())
