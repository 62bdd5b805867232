"""Pictures of results: plots and animation (matplotlib), and the seed's pydy.viz page."""
