"""Session runner and experiment runner of the hrc graph."""
