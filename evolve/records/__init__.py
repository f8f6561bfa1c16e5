"""What a run leaves on disk and how it is read back: the run folder (rundir), atomic writes
(files), champion.json (champion) and the champion as a runnable robot (replay), the verdict, where
each part of a run ran (segments), CPPN decoding, and older files brought to today's formats
(compact, legacy; `sgr migrate`: evolve/runs/migrate.py)."""
