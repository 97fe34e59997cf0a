"""Loaders for real carpet recordings and their video labels, into our dataset format."""
