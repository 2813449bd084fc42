"""Shared pieces of the hrc nodes: names, QoS, parameters, wrench axes."""
