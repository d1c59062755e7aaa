"""What one run hands the next: an identify report read back, what a design takes from it, prior data C₀."""
