"""Qt-free models of the explorer: the application state and what views compute from it."""
