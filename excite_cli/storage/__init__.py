"""Files the optimizer writes and reads: optimize results, exports, output paths."""
