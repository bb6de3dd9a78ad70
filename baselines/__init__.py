"""Classical depth controllers built on :mod:`subenv` only (thesis pole placement, gain scheduling,
a reversal-aware design, LQR). Empty until the baselines issue lands."""
