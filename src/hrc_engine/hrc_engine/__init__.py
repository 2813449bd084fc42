"""hrc_engine: a whole headless hrc session in one process, from the nodes ' pure cores."""
