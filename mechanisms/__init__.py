"""mechanisms: parametric models and the linkage analyses built on cspace."""
