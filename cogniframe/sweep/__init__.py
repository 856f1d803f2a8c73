"""Design-space exploration on Dask: `cogniframe sweep` and `cogniframe optimize`.

    sweepfile.py the sweep file (pydantic model, JSON Schema, errors naming file/key/line/fix)
    sample.py    grid / lhs / sobol (Saltelli) / random designs as dotted overrides
    evaluate.py  one design (and one batch) on a worker: overrides -> validate -> check -> row
    run.py       Dask orchestration: batches, resume, results.parquet
    optimize.py  optuna ask/tell in parallel batches on the same cluster; best.yaml; --cad
    report.py    pareto.png, sensitivity.png, summary.md

Nothing here is imported by `cogniframe check`; dask, pandas, pyarrow, optuna, SALib and
matplotlib are imported inside the functions that use them.
"""
