"""The four evogym benchmark tasks on top of tsim."""
