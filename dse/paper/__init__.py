"""The reproduction of Collinson & Sinnen 2017 (make paper, make paper-caches): drivers, the paper's numbers, report.md."""
