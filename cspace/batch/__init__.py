"""Defect margins for a whole batch of variants at once (placeholder index)."""
