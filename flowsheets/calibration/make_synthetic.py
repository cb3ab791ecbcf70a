"""Regenerates synthetic_gf25_table1.yaml and its CSV files: the headline scene at the 15 runs of paper 001,
Table 1 (8 corners for calibration, 6 face centres and the centre for validation) with the scene's default
parameters (Tables 8-10) as the truth, sampled every 5 min to 60 min, with Gaussian noise at the Table 5
standard deviations (seed 2024).

    PYTHONPATH=build/python python3 flowsheets/calibration/make_synthetic.py
"""
import os

from granuflow import calibration as cal, load

HERE = os.path.dirname(os.path.abspath(__file__))
fs = load(os.path.join(HERE, "..", "stoeckl_gf25_batch.yaml"))
es = cal.synthetic_experiments(fs, cal.table1_points(), seed=2024, name="synthetic_gf25_table1")
es.description = ("synthetic Table-1 runs of the headline scene: default parameters (paper 001, Tables 8-10) as the "
                  "truth, noise at the Table 5 standard deviations, seed 2024 (make_synthetic.py)")
cal.save_experiments(es, os.path.join(HERE, "synthetic_gf25_table1.yaml"), csv_dir="synthetic_gf25_table1")
