"""Drafts of configs for robots excite has never seen (``excite init``), above the optimizer whose
excitation problem they try out."""
