"""Datasets: the on-disk format, generation, statistics, and PyTorch loaders."""
