"""hrc_partners: cloned human models, cross-play, role allocation (pure cores + CLIs)."""
