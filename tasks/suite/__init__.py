"""One module per evogym task, each defining `SPEC` (a `tasks.spec.TaskSpec`) and its reward."""
