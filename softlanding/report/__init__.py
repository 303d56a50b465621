"""The reproduction of the paper and beyond: figures, tables and ``summary.md`` written into one
folder, and the demo."""
