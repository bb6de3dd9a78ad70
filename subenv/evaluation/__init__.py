"""Evaluation: the controller interface and registry, and the harness that compares controllers."""

from subenv.evaluation.controller import (
    Controller,
    ControllerFactory,
    controller_names,
    make_controller,
    register_controller,
)

__all__ = ["Controller", "ControllerFactory", "controller_names", "make_controller", "register_controller"]
