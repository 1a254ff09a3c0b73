"""diagnosis: ARRs with nominal and interval-uncertain parts, thresholds, signatures, detection (issue 3)."""
