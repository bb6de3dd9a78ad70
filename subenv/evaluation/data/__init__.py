"""The evaluation's data files: the certificates of achievable episodes
(:mod:`subenv.evaluation.achievable`)."""
