//! Figures of the prediction (paper Fig. 5-style phase diagram with r_trans, Fig. 7, Fig. 8).
