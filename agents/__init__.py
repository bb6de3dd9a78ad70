"""Stable-Baselines3 agents, configs, curriculum and trained models for the subenv environments.
Empty until the agents issue lands."""
