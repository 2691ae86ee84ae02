"""Applications on top of the framework: arch case files, assessment to collapse, repair
comparison and anchor layout search."""
