"""ament_python package smarticle_feedback: Tactile impact-threshold feedback controller for smarticles."""

from glob import glob

from setuptools import find_packages, setup

package_name = 'smarticle_feedback'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*']),
    package_data={package_name: ['py.typed']},
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        ('share/' + package_name + '/config', glob('config/*.yaml')),
    ],
    install_requires=['setuptools'],
    zip_safe=True,
    maintainer='Smarticle stack maintainers',
    maintainer_email='smarticles@example.org',
    description='Tactile impact-threshold feedback controller for smarticles.',
    license='Apache-2.0',
    python_requires='>=3.10',
    entry_points={
        'console_scripts': [
            'feedback = smarticle_feedback.feedback_node:main',
            'smarticle-feedback-calibrate = smarticle_feedback.impact_window:main',
        ],
    },
)
