"""The phases of an action's life, as the handle and the executive track them."""

PENDING, RUNNING, FINISHING, DONE = range(4)
