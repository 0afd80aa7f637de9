"""The output layer: documents, tables and formats built from results (no computation).

Numbers in CSV and JSON (:mod:`~wormgear_cli.output.formats`), tables as data
(:mod:`~wormgear_cli.output.tables`), and the documents of ``analyze``
(:mod:`~wormgear_cli.output.analyze`) and ``sweep`` (:mod:`~wormgear_cli.output.sweep`).
"""
