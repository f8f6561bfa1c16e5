"""Reports on finished runs: tables and statistics (report), how runs group (groups), plots and the
HTML gallery."""
