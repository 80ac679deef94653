"""The base scene of the runner tests: a block under a rigid indenter, pressed then pulled
sideways. Cases run through fake_case.py, so it is never solved; its keys are what the
tests sweep (contact.mu, contact.gamma, steps)."""
BLOCK_SCENE = """kind = "contact"
dim = 2
geometry = "block"
[contact]
mu = 0.2
[[steps]]
name = "press"
force = [0.0, -100.0]
[[steps]]
name = "pull"
force = [10.0, -100.0]
"""
