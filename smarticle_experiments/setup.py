"""ament_python package smarticle_experiments: the paper's experiments at scale on Dask (no ROS)."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'smarticle_experiments'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config/experiments', glob('config/experiments/*.yaml')),
        ('share/' + package_name + '/config', glob('config/*.csv')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='Smarticle stack maintainers',
    maintainer_email='smarticles@example.org',
    description="The paper's experiments at scale: specs as data, Dask engine, resumable store, reports.",
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'smarticle-experiments = smarticle_experiments.cli:main',
            'smarticle-calibrate = smarticle_experiments.calibrate_cli:main',
        ],
    },
)
