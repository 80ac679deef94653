"""Measurement programs: what femcontact's accuracy, speed and robustness are, measured in one run
each and written to results/ (`make bench`, `make bench_hertz_3d`, `make accuracy`, `make stability`,
`make plasticity`; `python -m benchmarks.NAME` from the repository root). They import femcontact;
femcontact never imports them."""
