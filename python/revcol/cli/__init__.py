"""The ``revcol`` command line: :mod:`.main` (the parser and the commands; ``revcol`` is
:func:`revcol.cli.main.main`), :mod:`.run` (``revcol run``), :mod:`.simulate` (``revcol
simulate``) and :mod:`.report` (the text reports).

Nothing outside this package imports from it: the library and the studies return reports
(dicts), and the command line prints them (``tests/python/test_imports.py`` checks it).
"""
