"""The command groups of ``tgsis``: each module owns its parsers (``add_NAME_parser``) and handlers."""
