"""The generators of scripts/claims.py: block name -> function returning the block's text, computed
from committed result sets only (claim_blocks/sets.py names them). One list, here."""
from . import appendix, gpu_model, packet, paper_tex, sampling

GENERATORS = {
    "paper-inconsistencies": paper_tex.inconsistencies_block,
    "gpu-model-table2": gpu_model.table2_block,
    "gpu-model-table3": gpu_model.table3_block,
    "gpu-model-table6": gpu_model.table6_block,
    "gpu-model-loso-per-scene": gpu_model.table2_loso_per_scene_phrase,
    "packet-correlation": packet.correlation_block,
    "packet-table2": packet.table2_block,
    "packet-table3": packet.table3_block,
    "packet-hcc-breakfast": packet.hcc_breakfast_phrase,
    "packet-shadow-gap": packet.shadow_gap_phrase,
    "spp-batches": sampling.batches_block,
    "spp-table7-anc": sampling.anc_table7_block,
    "spp-model-error": sampling.model_error_block,
    "spp-model-table2": sampling.model_table2_block,
    "spp-model-table3": sampling.model_table3_block,
    "viewport-lane-ratios": appendix.viewport_block,
    "hcc-dir-lane-ratios": appendix.hcc_dir_block,
    "hcc-dir-pocl-range": appendix.hcc_dir_pocl_phrase,
    "bounces-lane-efficiency": appendix.bounces_block,
    "bounces-pocl-range": appendix.bounces_pocl_phrase,
    "sweep-lambda": appendix.lambda_block,
    "sweep-twopoint": appendix.twopoint_block,
    "sweep-lambda-command": appendix.sweep_lambda_command_phrase,
    "sweep-commands": appendix.sweep_commands_block,
}
