"""The domain interface: skill-graph data types, the ``Domain`` object and its registry."""
