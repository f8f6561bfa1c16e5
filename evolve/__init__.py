"""Genomes and search (SGR and baselines) on top of tasks; also home of the `sgr` command line."""
