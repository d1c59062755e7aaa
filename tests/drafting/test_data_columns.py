"""The data columns an identify draft recognizes in a lab's file: every joint's or none, any case."""

from excite_cli.drafting.data_columns import recognized_columns


def test_excite_s_own_export_columns_are_recognized_with_their_units():
    names = ["time_s", "q_a_rad", "q_b_rad", "qd_a_rad_s", "qd_b_rad_s", "tau_a_Nm", "tau_b_Nm"]
    assert recognized_columns(names, ["a", "b"]) == {
        "time": "time_s",
        "q": ["q_a_rad", "q_b_rad"],
        "qd": ["qd_a_rad_s", "qd_b_rad_s"],
        "tau": ["tau_a_Nm", "tau_b_Nm"],
    }


def test_a_signal_one_joint_lacks_is_left_out_and_another_joint_s_column_never_taken():
    names = ["Timestamp", "A_POS", "b_pos", "effort_a", "effort_c"]
    assert recognized_columns(names, ["a", "b"]) == {"time": "Timestamp", "q": ["A_POS", "b_pos"]}
    assert recognized_columns(["x", "y"], ["a"]) == {}
